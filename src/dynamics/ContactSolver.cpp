// Sequential impulses over one step's contacts (docs/architecture.md, "Solver"), and the position
// correction that follows them.
#include <spall/dynamics/ContactSolver.h>

#include <spall/core/Parallel.h>
#include <spall/dynamics/Integrate.h>

#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <tuple>

namespace spall {

namespace {

/// Contacts are solved from the bottom of a stack up: along "up", against gravity (or out of the
/// ground where there is no gravity).
Eigen::Vector3d upDirection(const WorldSettings& world)
{
    return world.gravityMS2.squaredNorm() > 0 ? Eigen::Vector3d(-world.gravityMS2.normalized()) : world.ground.normal;
}

/// A contact as found: who, where, and what the solver should reach.
struct SolverContact {
    int a, b;                  ///< indices into the solver state; the world (ground, boxes) is its last entry
    std::pair<int64_t, int64_t> cacheKey;  ///< body ids, or body id and -2 - collider
    Eigen::Vector3d armA, armB;  ///< contact point relative to each centre of mass
    Eigen::Vector3d normal;      ///< pushes a away from b
    double bounceTarget = 0;
    double friction = 0;
    double height = 0;  ///< of the point along "up": a stack is solved from the bottom
};

/// One Jacobian row (normal or tangent) with each body's velocity response to a unit impulse.
struct SolverRow {
    Eigen::Vector3d dir, angularA, angularB, responseA, responseB;
    double mass;
};

/// Everything a sweep reads and writes of one contact, stored in solve order so that sweeps
/// stream through memory instead of jumping (a pile at 10^5 boundary voxels has ~20 000
/// contacts). The rows are precomputed in full: recomputing them from the arms in each sweep
/// saves memory but costs more time than it saves.
/// Left uninitialised on construction (filled in parallel).
struct SolverConstraint {
    int a, b;
    double bounceTarget, friction;
    double normalImpulse;     ///< accumulated
    Eigen::Vector2d frictionImpulse;  ///< accumulated, along the two tangent rows
    std::array<SolverRow, 3> rows;  ///< normal, then two fixed tangents
};

struct SolverBody {
    Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
    double invMass = 0;
    Eigen::Matrix3d invInertia = Eigen::Matrix3d::Zero();
};

/// Orders cached contact points by key, and keys against them.
struct ByKey {
    using Key = std::pair<int64_t, int64_t>;
    bool operator()(const ContactCache::Point& p, const Key& k) const { return p.key < k; }
    bool operator()(const Key& k, const ContactCache::Point& p) const { return k < p.key; }
};

/// Below this many contacts the solver runs on one thread (splitting costs more than it saves).
constexpr size_t kSplitSolverContacts = 4096;

/// The solver's halves: movable bodies below the median x of movable bodies are side 0, the
/// rest side 1, immovable ones -1 (they take no impulse). Everything is side 0 for small
/// problems. Decided by the scene alone.
std::vector<int> solverSides(const std::vector<Body>& bodies, size_t contactCount)
{
    std::vector<int> side(bodies.size(), -1);
    std::vector<std::pair<double, int>> xs;
    for (size_t i = 0; i < bodies.size(); ++i)
        if (takesContactImpulses(bodies[i])) xs.push_back({bodies[i].motion.positionM.x(), static_cast<int>(i)});
    if (contactCount < kSplitSolverContacts) {
        for (const auto& [x, i] : xs) side[i] = 0;
        return side;
    }
    const size_t half = xs.size() / 2;
    std::nth_element(xs.begin(), xs.begin() + half, xs.end());  // ties go by index: (x, i) pairs
    for (size_t k = 0; k < xs.size(); ++k) side[xs[k].second] = k < half ? 0 : 1;
    return side;
}

/// Sequential impulses over one step's contacts (docs/architecture.md, "Solver"). The contacts
/// are solved lowest first (Gauss–Seidel converges fastest up a stack that way); large problems
/// are cut in two halves that share no movable body, each solved on its own thread, and the
/// seam between them after both, so the result does not depend on the thread count.
class ImpulseSolver {
public:
    /// `state` ends with the world's immovable entry; `contacts` are in the order found.
    ImpulseSolver(const std::vector<Body>& bodies, std::vector<SolverBody>& state, const std::vector<SolverContact>& contacts)
        : mState(state), mContacts(contacts), mOrder(contacts.size()), mConstraints(new SolverConstraint[contacts.size()])
    {
        const int worldIndex = static_cast<int>(state.size()) - 1;
        const std::vector<int> side = solverSides(bodies, contacts.size());
        auto group = [&](const SolverContact& c) {
            const int sa = side[c.a], sb = c.b == worldIndex ? -1 : side[c.b];
            if (sa < 0) return sb < 0 ? 0 : sb;  // neither moves: any group will do
            return sb < 0 || sb == sa ? sa : 2;
        };
        struct SortKey {
            int group;
            double height;
            uint32_t contact;
            bool operator<(const SortKey& o) const
            {
                return group != o.group ? group < o.group : height != o.height ? height < o.height : contact < o.contact;
            }
        };
        std::vector<SortKey> sortKey(contacts.size());
        forEachIndex(contacts.size(), [&](size_t k) { sortKey[k] = {group(contacts[k]), contacts[k].height, static_cast<uint32_t>(k)}; }, kCheapGrain);
        tbb::parallel_sort(sortKey.begin(), sortKey.end());  // the keys are unique: the order is
        forEachIndex(contacts.size(), [&](size_t k) { mOrder[k] = sortKey[k].contact; }, kCheapGrain);
        for (const SortKey& key : sortKey) ++mGroupEnd[key.group];
        mGroupEnd[1] += mGroupEnd[0];
        mGroupEnd[2] += mGroupEnd[1];
        forEachIndex(contacts.size(), [&](size_t k) { mConstraints[k] = constraintOf(contacts[mOrder[k]]); }, kCheapGrain);
    }

    /// Starts each contact from the old point within a quarter voxel of it (in the first body's
    /// frame) and applies those impulses.
    void warmStart(const ContactCache& cache, const std::vector<Body>& bodies, const std::vector<Eigen::Matrix3d>& rotation)
    {
        const std::vector<ContactCache::Point>& old = cache.points;
        std::vector<uint32_t> position(mContacts.size());  // contact -> solve position
        forEachIndex(mContacts.size(), [&](size_t k) { position[mOrder[k]] = static_cast<uint32_t>(k); }, kCheapGrain);
        // Contacts are visited as found, so a pair's points look up their key once.
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mContacts.size(), 1024), [&](const tbb::blocked_range<size_t>& range) {
            std::pair<int64_t, int64_t> key(-1, -1);
            auto first = old.end(), last = old.end();
            for (size_t k = range.begin(); k != range.end(); ++k) {
                const SolverContact& c = mContacts[k];
                SolverConstraint& s = mConstraints[position[k]];
                if (s.rows[0].mass == 0) continue;
                if (k == range.begin() || c.cacheKey != key) {
                    key = c.cacheKey;
                    std::tie(first, last) = std::equal_range(old.begin(), old.end(), key, ByKey());
                }
                const Eigen::Vector3d local = rotation[c.a].transpose() * c.armA;
                const double near = 0.25 * bodies[c.a].voxelSizeM;
                const ContactCache::Point* best = nullptr;
                for (auto p = first; p != last; ++p)
                    if ((p->localM - local).norm() < near && (!best || (p->localM - local).norm() < (best->localM - local).norm())) best = &*p;
                if (!best) continue;
                s.normalImpulse = best->normalNs;
                const Eigen::Vector3d f = rotation[c.a] * best->frictionNs;
                s.frictionImpulse = Eigen::Vector2d(s.rows[1].dir.dot(f), s.rows[2].dir.dot(f));
            }
        });
        inGroups([&](size_t begin, size_t end) {
            for (size_t k = begin; k < end; ++k) {
                const SolverConstraint& s = mConstraints[k];
                push(s.rows[0], s, s.normalImpulse);
                for (int d = 1; d <= 2; ++d) push(s.rows[d], s, s.frictionImpulse[d - 1]);
            }
        });
    }

    void solve(int iterations)
    {
        for (int iteration = 0; iteration < iterations; ++iteration) inGroups([&](size_t begin, size_t end) { sweep(begin, end); });
    }

    /// The impulses reached, for the next step's warm start: sorted by key, within a key in
    /// solve order.
    void store(ContactCache& cache, const std::vector<Eigen::Matrix3d>& rotation) const
    {
        std::vector<std::pair<std::pair<int64_t, int64_t>, uint32_t>> byKey(mContacts.size());
        forEachIndex(mContacts.size(), [&](size_t k) { byKey[k] = {mContacts[mOrder[k]].cacheKey, static_cast<uint32_t>(k)}; }, kCheapGrain);
        tbb::parallel_sort(byKey.begin(), byKey.end());
        cache.points.resize(mContacts.size());
        forEachIndex(mContacts.size(), [&](size_t n) {
            const uint32_t k = byKey[n].second;
            const SolverContact& c = mContacts[mOrder[k]];
            const SolverConstraint& s = mConstraints[k];
            const Eigen::Vector3d friction = s.frictionImpulse[0] * s.rows[1].dir + s.frictionImpulse[1] * s.rows[2].dir;
            cache.points[n] = {c.cacheKey, rotation[c.a].transpose() * c.armA, s.normalImpulse, rotation[c.a].transpose() * friction};
        }, kCheapGrain);
    }

private:
    /// Jacobian rows (normal, then two fixed tangents, so friction converges like the normal
    /// does) with each body's velocity response to a unit impulse.
    SolverConstraint constraintOf(const SolverContact& c) const
    {
        SolverConstraint s;
        s.a = c.a;
        s.b = c.b;
        s.bounceTarget = c.bounceTarget;
        s.friction = c.friction;
        s.normalImpulse = 0;
        s.frictionImpulse.setZero();
        const Eigen::Vector3d t1 =
            (std::abs(c.normal.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(c.normal).normalized();
        const Eigen::Vector3d dirs[3] = {c.normal, t1, c.normal.cross(t1)};
        for (int d = 0; d < 3; ++d) {
            SolverRow& r = s.rows[d];
            r.dir = dirs[d];
            r.angularA = c.armA.cross(r.dir);
            r.angularB = c.armB.cross(r.dir);
            r.responseA = mState[c.a].invInertia * r.angularA;
            r.responseB = mState[c.b].invInertia * r.angularB;
            const double inv = mState[c.a].invMass + mState[c.b].invMass + r.angularA.dot(r.responseA) + r.angularB.dot(r.responseB);
            r.mass = inv > 0 ? 1.0 / inv : 0.0;
        }
        return s;
    }

    double relativeSpeed(const SolverRow& r, const SolverConstraint& c) const
    {
        return r.dir.dot(mState[c.a].v - mState[c.b].v) + r.angularA.dot(mState[c.a].w) - r.angularB.dot(mState[c.b].w);
    }

    /// Immovable entries are never written: both halves may read them at once.
    void push(const SolverRow& r, const SolverConstraint& c, double impulse)
    {
        if (mState[c.a].invMass > 0) {
            mState[c.a].v += mState[c.a].invMass * impulse * r.dir;
            mState[c.a].w += impulse * r.responseA;
        }
        if (mState[c.b].invMass > 0) {
            mState[c.b].v -= mState[c.b].invMass * impulse * r.dir;
            mState[c.b].w -= impulse * r.responseB;
        }
    }

    void sweep(size_t begin, size_t end)
    {
        for (size_t k = begin; k < end; ++k) {
            SolverConstraint& c = mConstraints[k];
            if (c.rows[0].mass == 0) continue;
            // Friction first (from the current normal impulse), then the normal, which matters
            // more: the accumulated tangential impulse stays in the Coulomb cone |f| <= mu N.
            Eigen::Vector2d accumulated = c.frictionImpulse;
            for (int d = 1; d <= 2; ++d) accumulated[d - 1] -= c.rows[d].mass * relativeSpeed(c.rows[d], c);
            const double limit = c.friction * c.normalImpulse;
            const double squared = accumulated.squaredNorm();
            if (squared > limit * limit) accumulated *= limit / std::sqrt(squared);
            for (int d = 1; d <= 2; ++d) push(c.rows[d], c, accumulated[d - 1] - c.frictionImpulse[d - 1]);
            c.frictionImpulse = accumulated;
            // Normal: the accumulated impulse stays >= 0.
            const double previous = c.normalImpulse;
            c.normalImpulse = std::max(previous + c.rows[0].mass * (c.bounceTarget - relativeSpeed(c.rows[0], c)), 0.0);
            push(c.rows[0], c, c.normalImpulse - previous);
        }
    }

    /// Runs f(begin, end) over the solve order: the two halves side by side, then the seam.
    template <typename F>
    void inGroups(const F& f)
    {
        tbb::parallel_invoke([&] { f(0, mGroupEnd[0]); }, [&] { f(mGroupEnd[0], mGroupEnd[1]); });
        f(mGroupEnd[1], mGroupEnd[2]);
    }

    std::vector<SolverBody>& mState;
    const std::vector<SolverContact>& mContacts;
    std::vector<uint32_t> mOrder;  ///< solve position -> contact
    size_t mGroupEnd[3] = {0, 0, 0};
    std::unique_ptr<SolverConstraint[]> mConstraints;  ///< in solve order
};

/// Solver state per body (velocities, inverse mass and world inverse inertia of the bodies that
/// take impulses), then the world's immovable entry; and every body's rotation.
std::vector<SolverBody> solverBodies(const std::vector<Body>& bodies, std::vector<Eigen::Matrix3d>& rotation)
{
    std::vector<SolverBody> state(bodies.size() + 1);
    rotation.resize(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
        const Body& body = bodies[i];
        rotation[i] = body.motion.orientation.toRotationMatrix();
        if (!takesContactImpulses(body)) continue;
        state[i] = {body.motion.linearVelocityMS, body.motion.angularVelocityRadS, 1.0 / body.mass.massKg,
                    rotation[i] * body.mass.inertiaKgM2.inverse() * rotation[i].transpose()};
    }
    return state;
}

/// The solver's contacts: static ones body by body, then the manifolds' points, each with the
/// velocity it should reach along its normal (a bounce, or closing at most the gap).
std::vector<SolverContact> solverContacts(const std::vector<Body>& bodies, const ContactSet& set, const std::vector<SolverBody>& state,
                                          const WorldSettings& world, const CollisionSettings& collisions, double dt)
{
    const int worldIndex = static_cast<int>(bodies.size());
    auto velocityAt = [&](int i, const Eigen::Vector3d& arm) -> Eigen::Vector3d { return state[i].v + state[i].w.cross(arm); };
    // Bounce only above the speed gravity adds in a couple of steps, so resting contacts rest.
    const double bounceThreshold = impactSpeedMS(world, dt);
    const Eigen::Vector3d up = upDirection(world);
    auto makeContact = [&](int a, int b, std::pair<int64_t, int64_t> key, const Eigen::Vector3d& armA, const Eigen::Vector3d& armB,
                           const Eigen::Vector3d& n, double depth, double restitution, double friction) {
        SolverContact c{a, b, key, armA, armB, n};
        const double vn = n.dot(velocityAt(a, armA) - velocityAt(b, armB));
        const double gap = std::max(-depth, 0.0);
        if (vn < -bounceThreshold && -vn * dt >= gap)
            c.bounceTarget = -restitution * vn;  // touches within this step: bounce
        else
            c.bounceTarget = -gap / dt;  // speculative: the approach may only close the gap
        c.friction = friction;
        c.height = up.dot(bodies[a].motion.positionM + armA);
        return c;
    };
    // Each source fills its own slots.
    std::vector<size_t> staticStart(bodies.size() + 1, 0), manifoldStart(set.manifolds.size() + 1, 0);
    for (size_t i = 0; i < bodies.size(); ++i) staticStart[i + 1] = staticStart[i] + set.statics[i].size();
    manifoldStart[0] = staticStart.back();
    for (size_t m = 0; m < set.manifolds.size(); ++m) manifoldStart[m + 1] = manifoldStart[m] + set.manifolds[m].points.size();
    std::vector<SolverContact> contacts(manifoldStart.back());
    forEachIndex(bodies.size(), [&](size_t i) {
        for (size_t n = 0; n < set.statics[i].size(); ++n) {
            const StaticContact& s = set.statics[i][n];
            contacts[staticStart[i] + n] = makeContact(static_cast<int>(i), worldIndex, {bodies[i].id, -2 - s.collider}, s.arm,
                                                       Eigen::Vector3d::Zero(), s.normal, s.depth, s.restitution, s.friction);
        }
    }, kCheapGrain);
    forEachIndex(set.manifolds.size(), [&](size_t m) {
        const ContactManifold& manifold = set.manifolds[m];
        const Body& a = bodies[manifold.a];
        const Body& b = bodies[manifold.b];
        for (size_t n = 0; n < manifold.points.size(); ++n) {
            const VoxelContact& p = manifold.points[n];
            contacts[manifoldStart[m] + n] = makeContact(manifold.a, manifold.b, {a.id, b.id}, p.pointM - a.motion.positionM, p.pointM - b.motion.positionM,
                                                         manifold.normal, p.depthM, collisions.restitution, collisions.friction);
        }
    }, kCheapGrain);
    return contacts;
}

}  // namespace

void solveContacts(std::vector<Body>& bodies, const ContactSet& set, const WorldSettings& world, const CollisionSettings& collisions,
                   double dt, ContactCache& cache)
{
    if (set.solverContacts == 0) {
        cache.points.clear();
        return;
    }
    std::vector<Eigen::Matrix3d> rotation;
    std::vector<SolverBody> state = solverBodies(bodies, rotation);
    const std::vector<SolverContact> contacts = solverContacts(bodies, set, state, world, collisions, dt);
    ImpulseSolver solver(bodies, state, contacts);
    solver.warmStart(cache, bodies, rotation);
    solver.solve(collisions.solverIterations);
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (!takesContactImpulses(bodies[i])) continue;
        bodies[i].motion.linearVelocityMS = state[i].v;
        bodies[i].motion.angularVelocityRadS = state[i].w;
    }
    solver.store(cache, rotation);
}

namespace {

/// Per body the inverse mass a correction moves it by (0: immovable, or a lattice, whose places
/// are its particles'), then the world's immovable entry.
std::vector<double> inverseMasses(const std::vector<Body>& bodies)
{
    std::vector<double> inverse(bodies.size() + 1, 0.0);
    for (size_t i = 0; i < bodies.size(); ++i)
        if (movable(bodies[i])) inverse[i] = 1.0 / bodies[i].mass.massKg;
    return inverse;
}

/// One overlap position correction removes: bodies a and b (bodies.size(): the immovable world).
struct PositionConstraint {
    int a, b;
    Eigen::Vector3d normal;
    double depthM, heightM;
};

/// Per movable body and static collider its deepest contact, per touching pair with a movable
/// body its manifold, from the bottom of the stack up.
std::vector<PositionConstraint> positionConstraints(const std::vector<Body>& bodies, const ContactSet& contacts, const WorldSettings& world,
                                                    const std::vector<double>& inverseMass)
{
    const int worldIndex = static_cast<int>(bodies.size());
    const Eigen::Vector3d up = upDirection(world);
    std::vector<PositionConstraint> constraints;
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (inverseMass[i] == 0.0) continue;  // a lattice's place is its particles'
        for (int collider = -1; collider < static_cast<int>(world.colliders.size()); ++collider) {
            const StaticContact* deepest = nullptr;
            for (const StaticContact& c : contacts.statics[i])
                if (c.collider == collider && (!deepest || c.depth > deepest->depth)) deepest = &c;
            if (deepest)
                constraints.push_back({static_cast<int>(i), worldIndex, deepest->normal, deepest->depth, up.dot(bodies[i].motion.positionM)});
        }
    }
    for (const ContactManifold& m : contacts.manifolds)
        if (inverseMass[m.a] + inverseMass[m.b] > 0)
            constraints.push_back({m.a, m.b, m.normal, m.maxDepthM, up.dot(bodies[m.a].motion.positionM + bodies[m.b].motion.positionM) / 2});
    std::stable_sort(constraints.begin(), constraints.end(), [](const PositionConstraint& x, const PositionConstraint& y) { return x.heightM < y.heightM; });
    return constraints;
}

/// Each movable body's overlap slack becomes its deepest overlap now if it has just left the
/// deformable phase, else the smaller of its slack and that overlap (0 without contacts).
void shrinkOverlapSlack(std::vector<Body>& bodies, const std::vector<PositionConstraint>& constraints, const std::vector<double>& inverseMass)
{
    std::vector<double> deepestM(bodies.size() + 1, 0.0);
    for (const PositionConstraint& c : constraints) {
        deepestM[c.a] = std::max(deepestM[c.a], c.depthM);
        deepestM[c.b] = std::max(deepestM[c.b], c.depthM);
    }
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (inverseMass[i] == 0.0) continue;
        double& slack = bodies[i].motion.overlapSlackM;
        slack = slack == kOverlapUnmeasured ? deepestM[i] : std::min(slack, deepestM[i]);
    }
}

/// The overlap a constraint excuses: against the world its body's slack; between two bodies the
/// smaller slack, so only pieces that left the phase overlapping each other keep overlapping. A
/// body in the phase has none (its slack is measured once it leaves).
double overlapSlackM(const std::vector<Body>& bodies, const PositionConstraint& c)
{
    const auto slackOf = [&](int i) { return std::max(bodies[size_t(i)].motion.overlapSlackM, 0.0); };
    return c.b == static_cast<int>(bodies.size()) ? slackOf(c.a) : std::min(slackOf(c.a), slackOf(c.b));
}

}  // namespace

void correctPositions(std::vector<Body>& bodies, const ContactSet& contacts, const WorldSettings& world)
{
    // A fifth of each overlap per step, as Box2D's and Jolt's position solvers take (their
    // Baumgarte factor, 0.2): removing it all at once pushed a light piece wedged under a slab
    // out sideways by centimetres a frame, and a pair whose normal turns from step to step
    // back and forth.
    constexpr double kCorrectedFraction = 0.2;
    if (bodies.empty()) return;
    const std::vector<double> inverseMass = inverseMasses(bodies);
    const std::vector<PositionConstraint> constraints = positionConstraints(bodies, contacts, world, inverseMass);
    shrinkOverlapSlack(bodies, constraints, inverseMass);
    const double slop = 0.01 * bodies.front().voxelSizeM;
    std::vector<Eigen::Vector3d> shift(inverseMass.size(), Eigen::Vector3d::Zero());
    for (int pass = 0; pass < 4; ++pass) {
        for (const PositionConstraint& c : constraints) {
            const double excessM = c.depthM - c.normal.dot(shift[c.a] - shift[c.b]) - overlapSlackM(bodies, c) - slop;
            if (excessM <= 0.0) continue;
            const double ia = inverseMass[c.a], ib = inverseMass[c.b];
            shift[c.a] += kCorrectedFraction * excessM * ia / (ia + ib) * c.normal;
            shift[c.b] -= kCorrectedFraction * excessM * ib / (ia + ib) * c.normal;
        }
    }
    for (size_t i = 0; i < bodies.size(); ++i) bodies[i].motion.positionM += shift[i];
}

}  // namespace spall
