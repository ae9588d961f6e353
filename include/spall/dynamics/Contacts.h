// Contacts (paper section 4.2): voxel-against-voxel detection between bodies, contacts with the
// ground and static boxes, and one sequential-impulse solver for all of them.
//
// Voxels collide as spheres of diameter h (the paper: centres closer than the voxel size). Three
// narrow phases find the same voxel pairs: the paper's pairwise test of every boundary voxel
// against every other, its buckets (a spatial hash of boundary voxels), and spall's own, which
// moves each boundary voxel of one body into the other body's index space and looks it up in that
// body's tree (O(1) per voxel). docs/architecture.md, "Collisions", says why.
#pragma once

#include <spall/dynamics/Dynamics.h>

#include <string>
#include <vector>

namespace spall {

enum class CollisionMethod { None, Pairwise, Buckets, TreeLookup };
CollisionMethod parseCollisionMethod(const std::string& name);  ///< none | pairwise | buckets | tree-lookup
std::string toString(CollisionMethod method);

struct CollisionSettings {
    CollisionMethod method = CollisionMethod::TreeLookup;
    double restitution = 0.2;   ///< between bodies (unit: fraction)
    double friction = 0.6;      ///< between bodies, Coulomb coefficient (unit: 1)
    int solverIterations = 12;  ///< sequential-impulse sweeps over all contacts
    /// The time step halves while any contact is deeper than this, and recovers when none is
    /// (the paper's adaptive step) (unit: voxels).
    double penetrationToleranceVoxels = 0.25;
};

/// One touching pair of voxels, world frame.
struct VoxelContact {
    Eigen::Vector3d pointM;   ///< midpoint of the two centres
    Eigen::Vector3d normal;   ///< unit, from body b's voxel to body a's
    double depthM;            ///< h minus the distance between the centres
};

/// The contacts of a pair of bodies reduced to at most four points sharing one normal.
struct ContactManifold {
    int a = -1, b = -1;  ///< body indices, a < b
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< from b to a
    std::vector<VoxelContact> points;
    double maxDepthM = 0;
    int64_t voxelContacts = 0;  ///< voxel pairs found before reduction
};

/// Pair of body indices, a < b.
struct BodyPair {
    int a, b;
    bool operator<(const BodyPair& o) const { return a != o.a ? a < o.a : b < o.b; }
    bool operator==(const BodyPair& o) const { return a == o.a && b == o.b; }
};

/// True when a contact between the two bodies could change anything: at least one of them moves.
bool pairCanInteract(const Body& a, const Body& b);

/// Broad phase: pairs whose bounding spheres overlap (sweep and prune along x) and that can
/// interact, sorted.
std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies);

/// Narrow phase by `method` (None gives nothing). Manifolds come sorted by pair; the result does
/// not depend on the thread count.
std::vector<ContactManifold> findBodyContacts(const std::vector<Body>& bodies, CollisionMethod method);

/// Reduces a pair's voxel contacts to a manifold: the normal is the depth-weighted mean of the
/// centre-line normals (their tangential parts cancel across a flat contact, which is what keeps
/// stacked debris from sliding), the points the deepest one and three that span the patch.
ContactManifold reduceManifold(int a, int b, const std::vector<VoxelContact>& contacts);

struct ContactStats {
    int64_t staticContacts = 0;   ///< voxel corners in the ground or a static box
    int64_t bodyContacts = 0;     ///< voxel pairs between bodies
    int64_t touchingPairs = 0;
    double maxPenetrationM = 0;   ///< deepest body-body contact before correction
};

/// Finds every contact of the bodies' current poses (ground, static boxes, other bodies), wakes
/// sleeping bodies that a moving one hits, solves them together with sequential impulses
/// (restitution, Coulomb friction; accumulated normal impulses stay non-negative), then removes
/// penetration by moving positions only, which adds no kinetic energy. Deterministic.
ContactStats resolveContacts(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                             const SleepSettings& sleep, double dtS);

}  // namespace spall
