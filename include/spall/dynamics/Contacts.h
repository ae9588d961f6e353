// Contacts (paper section 4.2): voxel-against-voxel detection between bodies, contacts with the
// ground and static boxes, and one sequential-impulse solver for all of them.
//
// Voxels collide as spheres of diameter h (the paper: centres closer than the voxel size); pairs a
// tenth of a voxel further apart are kept as speculative contacts. Three
// narrow phases find the same voxel pairs: the paper's pairwise test of every boundary voxel
// against every other, its buckets (a spatial hash of boundary voxels), and spall's own, which
// moves each boundary voxel of one body into the other body's index space and looks it up in that
// body's tree (O(1) per voxel). docs/architecture.md, "Collisions", says why.
#pragma once

#include <spall/dynamics/Dynamics.h>

#include <functional>
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
    /// h minus the distance between the centres; negative for a gap (contacts are found a tenth
    /// of a voxel early so that resting contacts do not flicker on and off)
    double depthM;
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

/// Broad phase: pairs whose bounding spheres overlap (found with a hierarchical grid) and that can
/// interact, sorted.
std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies);

/// Narrow phase by `method` (None gives nothing). Manifolds come sorted by pair; the result does
/// not depend on the thread count.
std::vector<ContactManifold> findBodyContacts(const std::vector<Body>& bodies, CollisionMethod method);

/// Reduces a pair's voxel contacts to a manifold: the normal is the depth-weighted mean of the
/// centre-line normals (their tangential parts cancel across a flat contact, which is what keeps
/// stacked debris from sliding), the points the deepest one and three that span the patch.
ContactManifold reduceManifold(int a, int b, const std::vector<VoxelContact>& contacts, double voxelSizeM);

struct ContactStats {
    int64_t staticContacts = 0;   ///< voxel corners in the ground or a static box
    int64_t bodyContacts = 0;     ///< voxel pairs between bodies
    int64_t solverContacts = 0;   ///< points the solver works on (static ones and the manifolds')
    double maxPenetrationM = 0;   ///< deepest body-body contact before correction
    std::vector<BodyPair> touching;  ///< pairs with contacts, sorted
};

/// The last step's contact points with their normal and friction impulses, keyed by the pair
/// of body ids (or body id and -2 - static collider); the next step's solver starts each new
/// point from the old point nearest to it in the first body's frame (warm starting), so a stack
/// holds its weight and a body on a slope its grip from the first iteration.
struct ContactCache {
    struct Point {
        std::pair<int64_t, int64_t> key;
        Eigen::Vector3d localM;  ///< in the first body's frame, relative to its centre of mass
        double normalNs = 0;
        Eigen::Vector3d frictionNs = Eigen::Vector3d::Zero();
    };
    /// Sorted by key (a flat list: rebuilding a hash map of lists every step cost a tenth of a
    /// step in a large pile).
    std::vector<Point> points;
};

/// Finds every contact of the bodies' current poses (ground, static boxes, other bodies), wakes
/// sleeping bodies that a moving one hits, solves them together with sequential impulses
/// (restitution, Coulomb friction; accumulated normal impulses stay non-negative), then removes
/// penetration by moving positions only, which adds no kinetic energy. Deterministic.
ContactStats resolveContacts(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                             const SleepSettings& sleep, double dtS, ContactCache* cache = nullptr);

/// Loads besides gravity and drag (the blast) on one body at a trial pose; `loaded` says
/// whether the body feels any this step (a loaded body does not sleep).
struct ExternalLoad {
    std::function<bool(const Body& body)> loaded;
    std::function<Wrench(const Body& body, double timeS, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& q)> wrench;
};

/// One step of every body: integrate (in parallel; gravity, drag and `load`), resolve contacts,
/// then sleep: bodies touching each other form islands, and an island sleeps when every body in
/// it has rested (fastest voxel below the sleep speed) for the sleep time. Deterministic for any
/// thread count.
ContactStats stepBodies(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                        const SleepSettings& sleep, Integrator integrator, double timeS, double dtS,
                        ContactCache* cache = nullptr, const ExternalLoad* load = nullptr);

}  // namespace spall
