// Fracture (paper sections 2.2 and 3.3): link loading by the blast, the paper's four algorithms,
// and splitting bodies into the connected components of their intact links.
#pragma once

#include <spall/blast/Blast.h>
#include <spall/fracture/Material.h>
#include <spall/fracture/Settings.h>
#include <spall/voxel/Body.h>

#include <cstdint>
#include <vector>

namespace spall {

/// Deterministic uniform number in [0, 1) from (seed, voxel, axis) (splitmix64 mixing).
double linkRandom(uint64_t seed, const openvdb::Coord& ijk, int axis);

/// Yield limit of a link before weakening and orientation (unit: Pa).
inline double baseYieldLimit(const Material& m, uint64_t seed, const openvdb::Coord& ijk, int axis)
{
    return m.meanYieldPa * (1.0 + m.yieldVariation * (2.0 * linkRandom(seed, ijk, axis) - 1.0));
}

/// What one step of loading did to one body.
struct LoadResult {
    int64_t brokenLinks = 0;
    int64_t brokenAnchors = 0;
    int64_t skippedLeaves = 0;  ///< not visited: the pressure there cannot change anything
};

/// Loads every intact link of `body` where the blast is now (`pressure`, a snapshot at the
/// step's start) and breaks or weakens it (generate in parallel over leaves, apply in leaf
/// order); the body's link count and anchored flag follow. Davison–Stevens accumulates the
/// body's damage grid over `dtS`. Yield limits derive from a hash of (`seed`, voxel, axis): the
/// scene's seed.
LoadResult loadLinks(Body& body, const Material& material, const PressureSnapshot& pressure, double dtS,
                     const FractureSettings& settings, uint64_t seed);

/// A zero damage grid with the body grid's topology (Davison–Stevens only).
DamageGrid::Ptr zeroDamageLike(const LinkGrid& grid);

/// Splits a body into the connected components of its intact links, each with its voxels'
/// damage. Each part gets the parent's velocity field at its own centre of mass (v + w x dc,
/// same w), so momentum is conserved. Returns an empty vector when the body is still one piece.
/// Part ids are left to the caller.
std::vector<Body> splitBody(const Body& body);

}  // namespace spall
