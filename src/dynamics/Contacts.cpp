#include <spall/dynamics/Contacts.h>

#include <spall/core/Error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace spall {

CollisionMethod parseCollisionMethod(const std::string& name)
{
    if (name == "none") return CollisionMethod::None;
    if (name == "pairwise") return CollisionMethod::Pairwise;
    if (name == "buckets") return CollisionMethod::Buckets;
    if (name == "tree-lookup") return CollisionMethod::TreeLookup;
    throw InputError("collision method '" + name + "' is unknown (expected none, pairwise, buckets or tree-lookup)");
}

std::string toString(CollisionMethod method)
{
    switch (method) {
    case CollisionMethod::None: return "none";
    case CollisionMethod::Pairwise: return "pairwise";
    case CollisionMethod::Buckets: return "buckets";
    case CollisionMethod::TreeLookup: return "tree-lookup";
    }
    return "tree-lookup";
}

namespace {

bool movable(const Body& body) { return !body.anchored && !body.asleep; }

/// Runs f(block) for blocks [0, count) in parallel; each block writes only its own slot.
template <typename F>
void forEachBlock(size_t count, const F& f)
{
    tbb::parallel_for(size_t(0), count, [&](size_t block) { f(block); });
}

// ---- narrow phase: spall's tree lookup -------------------------------------------------------

/// Boundary voxels of the body with fewer of them, moved into the other's index space and looked
/// up in its tree: the eight voxels around the moved centre are the only ones within one voxel.
std::vector<VoxelContact> treeLookupContacts(const Body& a, const Body& b)
{
    std::vector<VoxelContact> out;
    const bool probeIsA = a.boundaryVoxels.size() <= b.boundaryVoxels.size();
    const Body& probe = probeIsA ? a : b;
    const Body& target = probeIsA ? b : a;
    const double h = target.voxelSizeM;
    const Eigen::Matrix3d rp = probe.orientation.toRotationMatrix();
    const Eigen::Matrix3d rt = target.orientation.toRotationMatrix();
    // target index u = M i + t for probe index i (both bodies share the scene's voxel size).
    const Eigen::Matrix3d m = rt.transpose() * rp * (probe.voxelSizeM / h);
    const Eigen::Vector3d t =
        (rt.transpose() * (probe.positionM - target.positionM - rp * probe.mass.centreOfMassLocalM) + target.mass.centreOfMassLocalM) / h;
    const openvdb::CoordBBox& box = target.indexBounds;
    const Eigen::Vector3d lo(box.min().x() - 1.0, box.min().y() - 1.0, box.min().z() - 1.0);
    const Eigen::Vector3d hi(box.max().x() + 1.0, box.max().y() + 1.0, box.max().z() + 1.0);
    auto acc = target.grid->getConstAccessor();
    for (const openvdb::Coord& ijk : probe.boundaryVoxels) {
        const Eigen::Vector3d u = m * Eigen::Vector3d(ijk.x(), ijk.y(), ijk.z()) + t;
        if ((u.array() <= lo.array()).any() || (u.array() >= hi.array()).any()) continue;
        const openvdb::Coord base(static_cast<int>(std::floor(u.x())), static_cast<int>(std::floor(u.y())),
                                  static_cast<int>(std::floor(u.z())));
        for (int corner = 0; corner < 8; ++corner) {
            const openvdb::Coord k = base.offsetBy(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            if (!acc.isValueOn(k)) continue;
            const Eigen::Vector3d d = u - Eigen::Vector3d(k.x(), k.y(), k.z());
            const double d2 = d.squaredNorm();
            if (d2 >= 1.0) continue;
            const double dist = std::sqrt(d2);
            // From the target's voxel to the probe's; coincident centres fall back to the centres' line.
            Eigen::Vector3d n = dist > 1e-9 ? Eigen::Vector3d(rt * (d / dist)) : Eigen::Vector3d(probe.positionM - target.positionM);
            if (n.squaredNorm() < 1e-24) n = Eigen::Vector3d::UnitZ();
            n.normalize();
            const Eigen::Vector3d probeCentre = probe.voxelWorldM(ijk);
            VoxelContact c{probeCentre - 0.5 * dist * h * n, probeIsA ? n : Eigen::Vector3d(-n), (1.0 - dist) * h};
            out.push_back(c);
        }
    }
    return out;
}

// ---- narrow phase: the paper's baselines -----------------------------------------------------

struct WorldVoxel {
    Eigen::Vector3d centreM;
    int body;
};

/// Boundary voxels of every body, world centres, in body order.
std::vector<WorldVoxel> worldBoundaryVoxels(const std::vector<Body>& bodies)
{
    std::vector<size_t> offset(bodies.size() + 1, 0);
    for (size_t i = 0; i < bodies.size(); ++i) offset[i + 1] = offset[i] + bodies[i].boundaryVoxels.size();
    std::vector<WorldVoxel> voxels(offset.back());
    forEachBlock(bodies.size(), [&](size_t i) {
        for (size_t k = 0; k < bodies[i].boundaryVoxels.size(); ++k)
            voxels[offset[i] + k] = {bodies[i].voxelWorldM(bodies[i].boundaryVoxels[k]), static_cast<int>(i)};
    });
    return voxels;
}

struct PairContact {
    BodyPair pair;
    VoxelContact contact;
};

/// Contact between two world voxels closer than h, oriented from the higher body index to the lower.
bool voxelContact(const WorldVoxel& p, const WorldVoxel& q, double h, PairContact& out)
{
    const Eigen::Vector3d d = p.centreM - q.centreM;
    const double d2 = d.squaredNorm();
    if (d2 >= h * h) return false;
    const double dist = std::sqrt(d2);
    const bool pFirst = p.body < q.body;
    Eigen::Vector3d n = dist > 1e-9 * h ? Eigen::Vector3d(d / dist) : Eigen::Vector3d::UnitZ();
    if (!pFirst) n = -n;
    out.pair = {std::min(p.body, q.body), std::max(p.body, q.body)};
    out.contact = {0.5 * (p.centreM + q.centreM), n, h - dist};
    return true;
}

/// Groups pair contacts (already in a deterministic order) by pair and reduces each group.
std::vector<ContactManifold> manifoldsFromPairContacts(std::vector<PairContact>& all)
{
    std::stable_sort(all.begin(), all.end(), [](const PairContact& x, const PairContact& y) { return x.pair < y.pair; });
    std::vector<std::pair<size_t, size_t>> groups;
    for (size_t i = 0; i < all.size();) {
        size_t j = i;
        while (j < all.size() && all[j].pair == all[i].pair) ++j;
        groups.emplace_back(i, j);
        i = j;
    }
    std::vector<ContactManifold> manifolds(groups.size());
    forEachBlock(groups.size(), [&](size_t g) {
        std::vector<VoxelContact> contacts;
        for (size_t k = groups[g].first; k < groups[g].second; ++k) contacts.push_back(all[k].contact);
        manifolds[g] = reduceManifold(all[groups[g].first].pair.a, all[groups[g].first].pair.b, contacts);
    });
    return manifolds;
}

template <typename PerBlock>
std::vector<PairContact> collectInBlocks(size_t count, size_t blockSize, const PerBlock& perBlock)
{
    const size_t blocks = (count + blockSize - 1) / blockSize;
    std::vector<std::vector<PairContact>> found(blocks);
    forEachBlock(blocks, [&](size_t blk) { perBlock(blk * blockSize, std::min(count, (blk + 1) * blockSize), found[blk]); });
    std::vector<PairContact> all;
    for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
    return all;
}

/// The paper's first scheme: every boundary voxel against every boundary voxel of other bodies.
std::vector<ContactManifold> pairwiseContacts(const std::vector<Body>& bodies)
{
    const std::vector<WorldVoxel> voxels = worldBoundaryVoxels(bodies);
    if (voxels.empty()) return {};
    const double h = bodies.front().voxelSizeM;
    std::vector<char> moves(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) moves[i] = movable(bodies[i]);
    std::vector<PairContact> all = collectInBlocks(voxels.size(), 256, [&](size_t begin, size_t end, std::vector<PairContact>& out) {
        PairContact pc;
        for (size_t i = begin; i < end; ++i)
            for (size_t j = i + 1; j < voxels.size(); ++j)
                if (voxels[i].body != voxels[j].body && (moves[voxels[i].body] || moves[voxels[j].body]) &&
                    voxelContact(voxels[i], voxels[j], h, pc))
                    out.push_back(pc);
    });
    return manifoldsFromPairContacts(all);
}

/// The paper's second scheme: boundary voxels sorted into buckets of one voxel; each voxel is
/// tested against the voxels of its own and the 26 adjacent buckets.
std::vector<ContactManifold> bucketContacts(const std::vector<Body>& bodies)
{
    const std::vector<WorldVoxel> voxels = worldBoundaryVoxels(bodies);
    if (voxels.empty()) return {};
    const double h = bodies.front().voxelSizeM;
    auto cellOf = [&](const Eigen::Vector3d& x) {
        return openvdb::Coord(static_cast<int>(std::floor(x.x() / h)), static_cast<int>(std::floor(x.y() / h)),
                              static_cast<int>(std::floor(x.z() / h)));
    };
    auto key = [](const openvdb::Coord& c) {
        // 21 bits per axis: buckets one voxel wide over +-10^6 voxels.
        return (uint64_t(uint32_t(c.x()) & 0x1fffff) << 42) | (uint64_t(uint32_t(c.y()) & 0x1fffff) << 21) | uint64_t(uint32_t(c.z()) & 0x1fffff);
    };
    std::vector<std::pair<uint64_t, uint32_t>> table(voxels.size());
    for (size_t i = 0; i < voxels.size(); ++i) table[i] = {key(cellOf(voxels[i].centreM)), static_cast<uint32_t>(i)};
    std::sort(table.begin(), table.end());
    std::vector<char> moves(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) moves[i] = movable(bodies[i]);
    std::vector<PairContact> all = collectInBlocks(voxels.size(), 1024, [&](size_t begin, size_t end, std::vector<PairContact>& out) {
        PairContact pc;
        for (size_t i = begin; i < end; ++i) {
            const openvdb::Coord cell = cellOf(voxels[i].centreM);
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const uint64_t k = key(cell.offsetBy(dx, dy, dz));
                        auto it = std::lower_bound(table.begin(), table.end(), std::make_pair(k, uint32_t(0)));
                        for (; it != table.end() && it->first == k; ++it) {
                            const size_t j = it->second;
                            if (j <= i || voxels[i].body == voxels[j].body) continue;
                            if (!moves[voxels[i].body] && !moves[voxels[j].body]) continue;
                            if (voxelContact(voxels[i], voxels[j], h, pc)) out.push_back(pc);
                        }
                    }
        }
    });
    return manifoldsFromPairContacts(all);
}

// ---- contacts with the ground and static boxes -----------------------------------------------

struct SolverContact {
    int a, b;                  ///< b = -1: the world (ground or a static box)
    Eigen::Vector3d armA, armB;  ///< contact point relative to each centre of mass
    Eigen::Vector3d normal;      ///< pushes a away from b
    double bounceTarget = 0;
    double friction = 0;
    double normalImpulse = 0;
};

struct StaticContact {
    Eigen::Vector3d arm;
    Eigen::Vector3d normal;  ///< out of the collider
    double depth;
    int collider;  ///< -1: the ground; else the box index
    double restitution, friction;
};

/// Corners of the body's boundary voxels inside the ground or a static box.
std::vector<StaticContact> findStaticContacts(const Body& body, const WorldSettings& world)
{
    std::vector<StaticContact> contacts;
    const Eigen::Matrix3d rot = body.orientation.toRotationMatrix();
    const double h = body.voxelSizeM;
    const double voxelRadius = 0.5 * std::sqrt(3.0) * h;
    const GroundPlane& ground = world.ground;
    const bool nearGround = ground.enabled && ground.normal.dot(body.positionM) - ground.offsetM <= body.boundingRadiusM;
    std::vector<int> nearBoxes;
    for (size_t b = 0; b < world.colliders.size(); ++b) {
        const StaticBox& box = world.colliders[b];
        const Eigen::Vector3d local = box.orientation.inverse() * (body.positionM - box.centreM);
        const Eigen::Vector3d outside = (local.cwiseAbs() - box.halfExtentM).cwiseMax(0.0);
        if (outside.norm() <= body.boundingRadiusM) nearBoxes.push_back(static_cast<int>(b));
    }
    if (!nearGround && nearBoxes.empty()) return contacts;

    for (const openvdb::Coord& voxel : body.boundaryVoxels) {
        const Eigen::Vector3d centreArm = rot * body.voxelOffsetM(voxel);
        const Eigen::Vector3d centre = body.positionM + centreArm;
        // Eight corners per voxel: a face resting on a collider gets four points, so resting
        // bodies do not pivot about a single point.
        auto corners = [&](auto&& visit) {
            for (int c = 0; c < 8; ++c)
                visit(0.5 * h * (rot.col(0) * (c & 1 ? 1 : -1) + rot.col(1) * (c & 2 ? 1 : -1) + rot.col(2) * (c & 4 ? 1 : -1)));
        };
        if (nearGround && ground.normal.dot(centre) - ground.offsetM < voxelRadius) {
            corners([&](const Eigen::Vector3d& corner) {
                const double separation = ground.normal.dot(centre + corner) - ground.offsetM;
                if (separation < 0.0)
                    contacts.push_back({centreArm + corner, ground.normal, -separation, -1, ground.restitution, ground.friction});
            });
        }
        for (int b : nearBoxes) {
            const StaticBox& box = world.colliders[b];
            const Eigen::Matrix3d boxRot = box.orientation.toRotationMatrix();
            const Eigen::Vector3d local = boxRot.transpose() * (centre - box.centreM);
            if (((local.cwiseAbs() - box.halfExtentM).array() > voxelRadius).any()) continue;
            corners([&](const Eigen::Vector3d& corner) {
                const Eigen::Vector3d q = boxRot.transpose() * (centre + corner - box.centreM);
                const Eigen::Vector3d penetration = box.halfExtentM - q.cwiseAbs();
                if ((penetration.array() <= 0.0).any()) return;
                int axis = 0;
                penetration.minCoeff(&axis);
                const Eigen::Vector3d normal = boxRot.col(axis) * (q[axis] >= 0 ? 1.0 : -1.0);
                contacts.push_back({centreArm + corner, normal, penetration[axis], b, box.restitution, box.friction});
            });
        }
    }
    return contacts;
}

struct SolverBody {
    Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
    double invMass = 0;
    Eigen::Matrix3d invInertia = Eigen::Matrix3d::Zero();
};

}  // namespace

bool pairCanInteract(const Body& a, const Body& b) { return movable(a) || movable(b); }

std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies)
{
    struct Extent {
        double minX, maxX;
        int body;
    };
    std::vector<Extent> extents;
    extents.reserve(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
        const Body& b = bodies[i];
        extents.push_back({b.positionM.x() - b.boundingRadiusM, b.positionM.x() + b.boundingRadiusM, static_cast<int>(i)});
    }
    std::sort(extents.begin(), extents.end(),
              [](const Extent& x, const Extent& y) { return x.minX != y.minX ? x.minX < y.minX : x.body < y.body; });
    std::vector<BodyPair> pairs;
    for (size_t i = 0; i < extents.size(); ++i) {
        const Body& a = bodies[extents[i].body];
        for (size_t j = i + 1; j < extents.size() && extents[j].minX <= extents[i].maxX; ++j) {
            const Body& b = bodies[extents[j].body];
            if (!pairCanInteract(a, b)) continue;
            const double reach = a.boundingRadiusM + b.boundingRadiusM;
            if ((a.positionM - b.positionM).squaredNorm() > reach * reach) continue;
            pairs.push_back({std::min(extents[i].body, extents[j].body), std::max(extents[i].body, extents[j].body)});
        }
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

ContactManifold reduceManifold(int a, int b, const std::vector<VoxelContact>& contacts)
{
    ContactManifold m;
    m.a = a;
    m.b = b;
    m.voxelContacts = static_cast<int64_t>(contacts.size());
    if (contacts.empty()) return m;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    size_t deepest = 0;
    for (size_t i = 0; i < contacts.size(); ++i) {
        sum += contacts[i].depthM * contacts[i].normal;
        if (contacts[i].depthM > contacts[deepest].depthM) deepest = i;
    }
    m.maxDepthM = contacts[deepest].depthM;
    m.normal = sum.norm() > 1e-12 * m.maxDepthM ? Eigen::Vector3d(sum.normalized()) : contacts[deepest].normal;
    if (contacts.size() <= 4) {
        m.points = contacts;
        return m;
    }
    // Deepest, the farthest from it, the farthest from their line on each side: a quadrilateral
    // spanning the patch, as four points resist tipping as well as all of them.
    const Eigen::Vector3d p0 = contacts[deepest].pointM;
    size_t i1 = deepest;
    for (size_t i = 0; i < contacts.size(); ++i)
        if ((contacts[i].pointM - p0).squaredNorm() > (contacts[i1].pointM - p0).squaredNorm()) i1 = i;
    const Eigen::Vector3d edge = contacts[i1].pointM - p0;
    auto side = [&](size_t i) { return m.normal.dot(edge.cross(contacts[i].pointM - p0)); };
    size_t i2 = deepest, i3 = deepest;
    for (size_t i = 0; i < contacts.size(); ++i) {
        if (side(i) > side(i2)) i2 = i;
        if (side(i) < side(i3)) i3 = i;
    }
    for (size_t i : {deepest, i1, i2, i3}) {
        const bool seen = std::any_of(m.points.begin(), m.points.end(),
                                      [&](const VoxelContact& c) { return c.pointM == contacts[i].pointM; });
        if (!seen) m.points.push_back(contacts[i]);
    }
    return m;
}

std::vector<ContactManifold> findBodyContacts(const std::vector<Body>& bodies, CollisionMethod method)
{
    switch (method) {
    case CollisionMethod::None: return {};
    case CollisionMethod::Pairwise: return pairwiseContacts(bodies);
    case CollisionMethod::Buckets: return bucketContacts(bodies);
    case CollisionMethod::TreeLookup: break;
    }
    const std::vector<BodyPair> pairs = findCandidatePairs(bodies);
    std::vector<ContactManifold> found(pairs.size());
    forEachBlock(pairs.size(), [&](size_t i) {
        found[i] = reduceManifold(pairs[i].a, pairs[i].b, treeLookupContacts(bodies[pairs[i].a], bodies[pairs[i].b]));
    });
    std::vector<ContactManifold> manifolds;
    for (ContactManifold& m : found)
        if (!m.points.empty()) manifolds.push_back(std::move(m));
    return manifolds;
}

ContactStats resolveContacts(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                             const SleepSettings& sleep, double dt)
{
    ContactStats stats;
    const std::vector<ContactManifold> manifolds = findBodyContacts(bodies, collisions.method);
    // A moving body wakes a sleeping one it hits; a resting one leaves it asleep (and static).
    for (const ContactManifold& m : manifolds) {
        Body& a = bodies[m.a];
        Body& b = bodies[m.b];
        auto wakes = [&](const Body& mover) { return movable(mover) && maxVoxelSpeedMS(mover) > sleep.linearSpeedMS; };
        for (auto [sleeper, other] : {std::pair<Body*, Body*>{&a, &b}, std::pair<Body*, Body*>{&b, &a}})
            if (sleeper->asleep && !sleeper->anchored && wakes(*other)) {
                sleeper->asleep = false;
                sleeper->restTimeS = 0;
            }
    }

    std::vector<std::vector<StaticContact>> statics(bodies.size());
    forEachBlock(bodies.size(), [&](size_t i) {
        if (movable(bodies[i])) statics[i] = findStaticContacts(bodies[i], world);
    });

    std::vector<SolverBody> state(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
        const Body& body = bodies[i];
        if (!movable(body)) continue;
        const Eigen::Matrix3d rot = body.orientation.toRotationMatrix();
        state[i] = {body.linearVelocityMS, body.angularVelocityRadS, 1.0 / body.mass.massKg,
                    rot * body.mass.inertiaKgM2.inverse() * rot.transpose()};
    }
    auto velocityAt = [&](int i, const Eigen::Vector3d& arm) -> Eigen::Vector3d {
        return i < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(state[i].v + state[i].w.cross(arm));
    };
    // Bounce only above the speed gravity adds in a couple of steps, so resting contacts rest.
    const double bounceThreshold = 2.0 * world.gravityMS2.norm() * dt + 0.05;
    std::vector<SolverContact> contacts;
    auto addContact = [&](int a, int b, const Eigen::Vector3d& armA, const Eigen::Vector3d& armB, const Eigen::Vector3d& n,
                          double restitution, double friction) {
        SolverContact c{a, b, armA, armB, n};
        const double vn = n.dot(velocityAt(a, armA) - velocityAt(b, armB));
        if (vn < -bounceThreshold) c.bounceTarget = -restitution * vn;
        c.friction = friction;
        contacts.push_back(c);
    };
    for (size_t i = 0; i < bodies.size(); ++i) {
        stats.staticContacts += static_cast<int64_t>(statics[i].size());
        for (const StaticContact& s : statics[i])
            addContact(static_cast<int>(i), -1, s.arm, Eigen::Vector3d::Zero(), s.normal, s.restitution, s.friction);
    }
    for (const ContactManifold& m : manifolds) {
        stats.bodyContacts += m.voxelContacts;
        stats.maxPenetrationM = std::max(stats.maxPenetrationM, m.maxDepthM);
        for (const VoxelContact& p : m.points)
            addContact(m.a, m.b, p.pointM - bodies[m.a].positionM, p.pointM - bodies[m.b].positionM, m.normal,
                       collisions.restitution, collisions.friction);
    }
    stats.touchingPairs = static_cast<int64_t>(manifolds.size());
    if (contacts.empty()) return stats;

    auto inverseMassAlong = [&](int i, const Eigen::Vector3d& arm, const Eigen::Vector3d& dir) {
        if (i < 0) return 0.0;
        const Eigen::Vector3d rn = arm.cross(dir);
        return state[i].invMass + rn.dot(state[i].invInertia * rn);
    };
    auto applyImpulse = [&](const SolverContact& c, const Eigen::Vector3d& impulse) {
        state[c.a].v += state[c.a].invMass * impulse;
        state[c.a].w += state[c.a].invInertia * c.armA.cross(impulse);
        if (c.b >= 0) {
            state[c.b].v -= state[c.b].invMass * impulse;
            state[c.b].w -= state[c.b].invInertia * c.armB.cross(impulse);
        }
    };
    std::vector<double> normalMass(contacts.size());
    for (size_t k = 0; k < contacts.size(); ++k) {
        const SolverContact& c = contacts[k];
        const double inv = inverseMassAlong(c.a, c.armA, c.normal) + inverseMassAlong(c.b, c.armB, c.normal);
        normalMass[k] = inv > 0 ? 1.0 / inv : 0.0;
    }
    for (int iteration = 0; iteration < collisions.solverIterations; ++iteration) {
        for (size_t k = 0; k < contacts.size(); ++k) {
            SolverContact& c = contacts[k];
            if (normalMass[k] == 0) continue;
            // Normal: the accumulated impulse stays >= 0.
            const double vn = c.normal.dot(velocityAt(c.a, c.armA) - velocityAt(c.b, c.armB));
            const double previous = c.normalImpulse;
            c.normalImpulse = std::max(previous + normalMass[k] * (c.bounceTarget - vn), 0.0);
            applyImpulse(c, (c.normalImpulse - previous) * c.normal);
            // Friction along the current sliding direction, bounded by mu times the normal impulse.
            const Eigen::Vector3d vr = velocityAt(c.a, c.armA) - velocityAt(c.b, c.armB);
            const Eigen::Vector3d vt = vr - c.normal.dot(vr) * c.normal;
            const double speed = vt.norm();
            if (speed < 1e-12) continue;
            const Eigen::Vector3d t = vt / speed;
            const double inv = inverseMassAlong(c.a, c.armA, t) + inverseMassAlong(c.b, c.armB, t);
            const double limit = c.friction * c.normalImpulse;
            applyImpulse(c, std::clamp(-speed / inv, -limit, limit) * t);
        }
    }
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (!movable(bodies[i])) continue;
        bodies[i].linearVelocityMS = state[i].v;
        bodies[i].angularVelocityRadS = state[i].w;
    }

    // Position correction (velocities untouched, so no kinetic energy is added): per body and
    // static collider along its deepest contact's normal, then per pair of bodies split by
    // inverse mass along the manifold normal.
    const double slop = 0.01 * (bodies.empty() ? 0.0 : bodies.front().voxelSizeM);
    for (size_t i = 0; i < bodies.size(); ++i) {
        for (int collider = -1; collider < static_cast<int>(world.colliders.size()); ++collider) {
            const StaticContact* deepest = nullptr;
            for (const StaticContact& c : statics[i])
                if (c.collider == collider && (!deepest || c.depth > deepest->depth)) deepest = &c;
            if (deepest && deepest->depth > slop) bodies[i].positionM += (deepest->depth - slop) * deepest->normal;
        }
    }
    for (const ContactManifold& m : manifolds) {
        const double total = state[m.a].invMass + state[m.b].invMass;
        if (m.maxDepthM <= slop || total == 0) continue;
        const double correction = m.maxDepthM - slop;
        bodies[m.a].positionM += correction * state[m.a].invMass / total * m.normal;
        bodies[m.b].positionM -= correction * state[m.b].invMass / total * m.normal;
    }
    return stats;
}

}  // namespace spall
