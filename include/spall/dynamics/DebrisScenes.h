// Generated debris scenes for the collision benchmark and the stability tests: a pile of cubic
// fragments resting on each other in a box, and the same fragments flying apart.
#pragma once

#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <cstdint>
#include <vector>

namespace spall {

struct DebrisScene {
    std::vector<Body> bodies;
    WorldSettings world;  ///< ground at z = 0; the pile's container walls as static boxes
    int64_t boundaryVoxels = 0;
};

/// `fragments` cubes of `edgeVoxels`^3 voxels (side h) stacked in staggered layers inside a
/// square container just wider than the pile, each turned a little about z, dropped from a
/// hundredth of their size. Seeded, so the same arguments give the same scene.
DebrisScene makeDebrisPile(int fragments, int edgeVoxels, double voxelSizeM, uint64_t seed);

/// The same fragments packed into a cube in the air, flying out from its centre at up to
/// `speedMS` (plus a tenth of it at random), spinning, above an open ground.
DebrisScene makeExplosionCloud(int fragments, int edgeVoxels, double voxelSizeM, double speedMS, uint64_t seed);

}  // namespace spall
