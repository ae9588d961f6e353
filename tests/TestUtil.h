#pragma once

#include <spall/fracture/Fracture.h>
#include <spall/voxel/VdbIo.h>
#include <spall/voxel/Body.h>
#include <spall/world/StaticWorld.h>

#include <openvdb/openvdb.h>

#include <initializer_list>
#include <vector>

namespace spall::test {

/// A linked grid from an explicit list of voxels.
inline LinkGrid::Ptr gridFromVoxels(std::initializer_list<openvdb::Coord> voxels, double h = 1.0)
{
    initialiseOpenVdb();
    LinkGrid::Ptr g = LinkGrid::create(0);
    g->setTransform(openvdb::math::Transform::createLinearTransform(h));
    for (const auto& c : voxels) g->tree().setValueOn(c, 0);
    linkAllNeighbours(*g);
    return g;
}

/// A solid box of nx*ny*nz voxels starting at the origin, all links intact.
inline LinkGrid::Ptr boxGrid(int nx, int ny, int nz, double h = 1.0)
{
    initialiseOpenVdb();
    LinkGrid::Ptr g = LinkGrid::create(0);
    g->setTransform(openvdb::math::Transform::createLinearTransform(h));
    g->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(nx - 1, ny - 1, nz - 1)), 0, true);
    linkAllNeighbours(*g);
    return g;
}

/// A solid box body of nx*ny*nz voxels of side h, its centre of mass at `positionM`.
inline Body boxBody(int nx, int ny, int nz, double h, double densityKgM3, const Eigen::Vector3d& positionM = Eigen::Vector3d::Zero(),
                    const Eigen::Quaterniond& orientation = Eigen::Quaterniond::Identity())
{
    Body b = makeBody(boxGrid(nx, ny, nz, h), h, densityKgM3);
    b.motion.positionM = positionM;
    b.motion.orientation = orientation;
    return b;
}

/// A 4 x 1 x 1 bar broken between voxels 1 and 2: its two halves (each with one fracture face),
/// numbered firstId and firstId + 1.
inline std::vector<Body> barBrokenInTwo(Body bar, int64_t firstId)
{
    auto acc = bar.grid->getAccessor();
    breakLink(acc, openvdb::Coord(1, 0, 0), kPosX);
    std::vector<Body> halves = splitBody(bar);
    for (size_t i = 0; i < halves.size(); ++i) halves[i].id = firstId + int64_t(i);
    return halves;
}

/// A static world of the ground plane z = 0 alone.
inline StaticWorld groundAtZero()
{
    StaticWorld world;
    world.ground = GroundPlane{true, Eigen::Vector3d::UnitZ(), 0.0};
    return world;
}

/// A small scene run through in a second: a 2 m brick wall at 10 cm voxels, anchored, 3 kg of
/// TNT on the ground 2 m before it, and a turned collider behind it.
inline constexpr const char* kSmallScene = R"({
  "voxel_size_m": 0.1, "duration_s": 0.5, "frame_rate_hz": 24, "seed": 3,
  "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [2.0, 0.3, 1.5]},
               "position_m": [0, 0, 0.75], "material": "brick-masonry", "anchor": "ground"}],
  "charges": [{"position_m": [0.2, -2.0, 0.0], "tnt_kg": 3.0, "burst": "surface"}],
  "colliders": [{"position_m": [0, 3, 0.5], "size_m": [4, 0.5, 1], "rotation_deg": [0, 0, 10]}]
})";

/// A piece of brick masonry 6 × 4 × 3 voxels of 2.5 cm, turned so that a corner leads, its centre
/// 12 cm up (its lowest corner 2.6 cm), thrown along the ground at 4 m/s and down at 0.5 m/s,
/// spinning, with impact fracture: its lattice enters for the ground's impact and coasts until
/// its particles meet the ground (DeformableBody::coasting).
inline constexpr const char* kPieceThrownCornerFirstAlongTheGround = R"({
  "voxel_size_m": 0.025, "frame_rate_hz": 50,
  "objects": [{"primitive": {"shape": "box", "size_m": [0.15, 0.1, 0.075]}, "position_m": [0, 0, 0.12],
               "rotation_deg": [45, 35, 10], "linear_velocity_m_s": [0, 4, -0.5], "angular_velocity_rad_s": [0, 0, 3],
               "material": "brick-masonry"}],
  "fracture": {"algorithm": "lattice"},
  "lattice": {"impact_fracture": true}
})";

}  // namespace spall::test
