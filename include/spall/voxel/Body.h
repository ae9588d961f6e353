// Connected-voxel bodies (paper section 3.2).
//
// A body is an OpenVDB grid in its own index space: active voxels are solid material and each
// voxel's value holds link bits to its six face neighbours (kept symmetric) plus one anchor bit
// bonding the voxel to the world. A fragment keeps its parent's index space, so splitting copies no
// geometry and the exported index-to-world map is exact.
#pragma once

#include <spall/voxel/LinkBits.h>

#include <openvdb/openvdb.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <vector>

namespace spall {

/// Active voxel = solid; value = link bits. Bodies use a shallow tree (8^3 leaves under two 8^3
/// internal levels): a one-voxel fragment then costs about 10 KB instead of the ~300 KB of
/// OpenVDB's standard 5-4-3 tree, which matters when a blast makes thousands of fragments.
/// Files hold standard FloatGrids (voxel/VdbIo.h), which every reader knows.
using LinkTree = openvdb::tree::Tree4<int32_t, 3, 3, 3>::Type;
using LinkGrid = openvdb::Grid<LinkTree>;
using LinkLeaf = LinkTree::LeafNodeType;
/// Per-voxel Davison–Stevens damage, same shallow configuration.
using DamageTree = openvdb::tree::Tree4<float, 3, 3, 3>::Type;
using DamageGrid = openvdb::Grid<DamageTree>;
/// Per voxel, the damage of the deformable phase's bonds (0 intact … 1 broken) across its +x,
/// +y and +z faces and of its anchor's bond (components 0–2 and 3), same shallow configuration.
using LinkDamageTree = openvdb::tree::Tree4<openvdb::Vec4s, 3, 3, 3>::Type;
using LinkDamageGrid = openvdb::Grid<LinkDamageTree>;
/// The component of LinkDamageTree's values that holds the anchor's bond.
constexpr int kAnchorDamage = 3;

/// Activates in `target` every active voxel of `source` with `value` (any configurations with 8^3
/// leaves; `source` must hold no active tiles).
template <typename TargetTreeT, typename SourceTreeT>
void copyActiveTopology(TargetTreeT& target, const SourceTreeT& source, typename TargetTreeT::ValueType value)
{
    for (auto leaf = source.cbeginLeaf(); leaf; ++leaf) {
        auto* out = target.touchLeaf(leaf->origin());
        for (auto it = leaf->cbeginValueOn(); it; ++it) out->setValueOn(it.pos(), value);
    }
}


/// Mass properties of voxels taken as solid cubes of side h.
struct MassProperties {
    int64_t voxelCount = 0;
    double massKg = 0.0;
    /// Centre of mass in the body's local frame, local = index * h (unit: m).
    Eigen::Vector3d centreOfMassLocalM = Eigen::Vector3d::Zero();
    /// Inertia tensor about the centre of mass, local axes (unit: kg m^2).
    Eigen::Matrix3d inertiaKgM2 = Eigen::Matrix3d::Zero();
};

/// An exposed face: the neighbour across it is not in the body. Cached per body; it changes
/// only when the body splits.
struct ExposedFace {
    openvdb::Coord voxel;
    int face;
};

/// A body's hot state: what every step reads and writes (Box2D keeps it apart from shape data).
struct BodyMotion {
    Eigen::Vector3d positionM = Eigen::Vector3d::Zero();  ///< centre of mass, world frame (unit: m)
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< local to world
    Eigen::Vector3d linearVelocityMS = Eigen::Vector3d::Zero();       ///< (unit: m/s)
    Eigen::Vector3d angularVelocityRadS = Eigen::Vector3d::Zero();    ///< world frame (unit: rad/s)
    bool asleep = false;
    /// In the deformable phase: its lattice moves it (lattice/Deformable.h) and the rigid phases
    /// leave it alone.
    bool deformable = false;
    double restTimeS = 0.0;  ///< how long the body has been below the sleep thresholds (unit: s)
    /// The fastest impact it has taken as a lattice (lattice.impact_fracture), which its parts
    /// inherit: one no faster grows no damage (a bond's damage follows the largest strain it has
    /// reached), so it stays rigid (unit: m/s).
    double survivedImpactMS = 0.0;
    /// How deep it may overlap the ground, a collider or another body without being pushed out
    /// (correctPositions): what it overlapped when it left the deformable phase, shrinking as the
    /// overlap does. Its lattice's particles met each other as spheres and the ground as unturned
    /// cubes where its voxels are turned cubes, so a piece leaves overlapping by up to a fifth of
    /// a voxel; pushing that out lifts stacks out of nothing (unit: m; kOverlapUnmeasured:
    /// measured at its next contacts).
    double overlapSlackM = 0.0;
};

/// BodyMotion::overlapSlackM of a body that has just left the deformable phase.
inline constexpr double kOverlapUnmeasured = -1.0;

/// No body: a parent id of a body the scene made, or a part's id before the simulation gives it one.
inline constexpr int64_t kNoBodyId = -1;

/// One rigid body of connected voxels: its motion, its shape (grid, per-voxel state), and what is
/// derived from the shape, which only refreshDerivedData writes. Every body of a simulation has
/// the same voxel size (the scene's; fragments inherit it): the contact code relies on that and
/// requireVoxelSize checks it where a simulation starts.
struct Body {
    int64_t id = 0;
    int64_t parentId = kNoBodyId;
    int materialIndex = 0;
    BodyMotion motion;

    // Shape.
    LinkGrid::Ptr grid;
    /// Per-voxel Davison–Stevens damage, same topology as the grid; only for that fracture rule
    /// (else null). It follows the voxels through every split.
    DamageGrid::Ptr damage;
    /// The damage its lattice left in the bonds that survived the deformable phase, same
    /// topology as the grid (null: none), so a body that enters the phase again starts as weak
    /// as it left (Lattice::fromBody). It follows the voxels through every split.
    LinkDamageGrid::Ptr linkDamage;
    double voxelSizeM = 0.1;
    double densityKgM3 = 1000.0;

    // Derived from the shape (refreshDerivedData).
    MassProperties mass;
    /// Radius of the sphere about the centre of mass that holds every voxel (unit: m).
    double boundingRadiusM = 0.0;
    bool anchored = false;
    int64_t linkCount = 0;  ///< intact links; a body without links or anchors cannot fracture
    std::vector<ExposedFace> exposedFaces;
    /// Voxels with an exposed face, in leaf order: the only ones that can touch another body.
    std::vector<openvdb::Coord> boundaryVoxels;
    /// Index-space bounds of the active voxels.
    openvdb::CoordBBox indexBounds;

    /// Local (index * h) position of a voxel centre relative to the centre of mass (unit: m).
    Eigen::Vector3d voxelOffsetM(const openvdb::Coord& ijk) const
    {
        return Eigen::Vector3d(ijk.x(), ijk.y(), ijk.z()) * voxelSizeM - mass.centreOfMassLocalM;
    }
    Eigen::Vector3d voxelWorldM(const openvdb::Coord& ijk) const
    {
        return motion.positionM + motion.orientation * voxelOffsetM(ijk);
    }
    /// How far the lowest point of a voxel's cube lies above the plane normal · x = offset (unit: m).
    double voxelHeightAbovePlaneM(const openvdb::Coord& ijk, const Eigen::Vector3d& normal, double offsetM) const
    {
        const Eigen::Matrix3d r = motion.orientation.toRotationMatrix();
        const double halfDepthM = 0.5 * voxelSizeM * (std::abs(normal.dot(r.col(0))) + std::abs(normal.dot(r.col(1))) + std::abs(normal.dot(r.col(2))));
        return normal.dot(voxelWorldM(ijk)) - halfDepthM - offsetM;
    }
    Eigen::Matrix3d worldInertiaKgM2() const
    {
        const Eigen::Matrix3d r = motion.orientation.toRotationMatrix();
        return r * mass.inertiaKgM2 * r.transpose();
    }
    /// The exact index-to-world map, as OpenVDB's transform (row-vector convention).
    openvdb::math::Transform::Ptr indexToWorld() const;
};

/// Sets the link bits of every active voxel to match its active face neighbours.
void linkAllNeighbours(LinkGrid& grid);

/// Number of intact links, each counted once.
int64_t countLinks(const LinkGrid& grid);

/// Breaks the link across `face` of `ijk` on both sides. Returns false if it was already broken.
bool breakLink(LinkGrid::Accessor& acc, const openvdb::Coord& ijk, int face);

/// True when every link bit is matched by its neighbour's bit and only joins active voxels.
bool linksAreSymmetric(const LinkGrid& grid);

MassProperties computeMassProperties(const LinkGrid& grid, double voxelSizeM, double densityKgM3);

/// All exposed faces, in leaf order (deterministic).
std::vector<ExposedFace> collectExposedFaces(const LinkGrid& grid);

/// Voxels with at least one exposed face, in leaf order (faces as collectExposedFaces gives them).
std::vector<openvdb::Coord> boundaryVoxelsOf(const std::vector<ExposedFace>& faces);

/// True when some voxel holds the anchor bit.
bool hasAnchoredVoxel(const LinkGrid& grid);

/// Fills everything derived from the grid — mass properties, exposed faces, boundary voxels,
/// bounds, bounding radius, link count, anchored flag — the one function that does (on creation,
/// on a split, on reading a checkpoint).
void refreshDerivedData(Body& body);

/// Throws InputError naming the first body whose voxel size is not `voxelSizeM`.
void requireVoxelSize(const std::vector<Body>& bodies, double voxelSizeM);

/// A body from a grid placed so that its local frame maps to the world by translation only.
Body makeBody(LinkGrid::Ptr grid, double voxelSizeM, double densityKgM3);

}  // namespace spall
