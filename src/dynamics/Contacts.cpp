#include <spall/dynamics/Contacts.h>

#include <spall/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <tuple>
#include <chrono>
#include <cstdio>

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

/// Contacts are found this far (in voxels) before they touch and solved speculatively (the
/// approach may only close the gap), so a resting contact does not flicker on and off.
constexpr double kContactMarginVoxels = 0.1;
/// Voxel pairs closer than this (in voxels) are tested as cubes. The paper's one voxel misses
/// turned cubes touching corner to edge, which then sink into each other unseen; sqrt(2) plus
/// the margin catches every pair turned about one axis, and what it misses across a body
/// diagonal overlaps by under a quarter voxel.
constexpr double kReach = 1.4143 + kContactMarginVoxels;

/// Runs f(k) for k in [0, count) in parallel; each k writes only its own slot. Tasks take at
/// least `grain` indices: 1 where f does much (a body, a pair), kCheapGrain where it does little.
template <typename F>
void forEachIndex(size_t count, const F& f, size_t grain = 1)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, grain), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k != range.end(); ++k) f(k);
    });
}
constexpr size_t kCheapGrain = 1024;

// ---- the contact between two voxels ----------------------------------------------------------

/// Not registered with the tree (registration costs a locked hash-map insert per pair).
using ConstLinkAccessor = openvdb::tree::ValueAccessor<const LinkTree, false>;

/// The separating axes of a voxel of body a against one of body b (rotations ra, rb) and the
/// cubes' projected radius along each: the six face axes, then the edge-edge axes that are not
/// parallel to a face axis. Every voxel pair of a body pair shares them, so they are built once
/// per pair.
struct CubePairAxes {
    std::array<Eigen::Vector3d, 15> axis;
    std::array<double, 15> radius;
    int count = 0;

    CubePairAxes(const Eigen::Matrix3d& ra, const Eigen::Matrix3d& rb, double h)
    {
        // c(i, j) = a's axis i . b's axis j; every projected radius follows from it.
        const Eigen::Matrix3d c = ra.transpose() * rb;
        const Eigen::Matrix3d absC = c.cwiseAbs();
        const double half = 0.5 * h;
        for (int i = 0; i < 3; ++i) add(ra.col(i), half * (1.0 + absC.row(i).sum()));
        for (int j = 0; j < 3; ++j) add(rb.col(j), half * (1.0 + absC.col(j).sum()));
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double sine2 = 1.0 - c(i, j) * c(i, j);
                if (sine2 < 1e-6) continue;  // parallel edges: a face axis covers it
                const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
                const double norm = std::sqrt(sine2);
                add(ra.col(i).cross(rb.col(j)) / norm, half * (absC(i1, j) + absC(i2, j) + absC(i, j1) + absC(i, j2)) / norm);
            }
    }

private:
    void add(const Eigen::Vector3d& unitAxis, double r)
    {
        axis[count] = unitAxis;
        radius[count] = r;
        ++count;
    }
};

/// Contact of a voxel of body a with one of body b, given the world vector from b's voxel centre
/// to a's. The voxels are cubes: the normal is the axis along which they overlap least
/// (separating-axis test), the depth that overlap (negative: a gap). The paper's line between
/// centres tilts whenever two faces meet offset by a fraction of a voxel, and tilted normals make
/// resting debris slide and rattle. Returns false when the cubes are separated by more than the
/// speculative margin.
bool makeVoxelContact(const CubePairAxes& axes, double h, const Eigen::Vector3d& centreA, const Eigen::Vector3d& bToA,
                      VoxelContact& out)
{
    const double separated = -kContactMarginVoxels * h;
    double best = std::numeric_limits<double>::infinity();
    int bestAxis = 0;
    double bestAlong = 0;
    for (int k = 0; k < axes.count; ++k) {
        const double along = axes.axis[k].dot(bToA);
        const double overlap = axes.radius[k] - std::abs(along);
        if (overlap < best) {
            best = overlap;
            bestAxis = k;
            bestAlong = along;
            if (best <= separated) return false;
        }
    }
    const Eigen::Vector3d normal = bestAlong >= 0 ? axes.axis[bestAxis] : Eigen::Vector3d(-axes.axis[bestAxis]);
    out = {centreA - 0.5 * bToA, normal, best};
    return true;
}

/// At most four of the contacts: the deepest, the farthest from it, and the farthest from their
/// line on each side; a quadrilateral spanning the patch resists tipping as well as all of them,
/// and fewer, distinct points let the solver converge faster.
std::vector<size_t> spanningPoints(const std::vector<VoxelContact>& contacts, const Eigen::Vector3d& normal, size_t deepest)
{
    if (contacts.size() <= 4) {
        std::vector<size_t> all(contacts.size());
        for (size_t i = 0; i < all.size(); ++i) all[i] = i;
        return all;
    }
    const Eigen::Vector3d p0 = contacts[deepest].pointM;
    size_t i1 = deepest;
    for (size_t i = 0; i < contacts.size(); ++i)
        if ((contacts[i].pointM - p0).squaredNorm() > (contacts[i1].pointM - p0).squaredNorm()) i1 = i;
    const Eigen::Vector3d edge = contacts[i1].pointM - p0;
    auto side = [&](size_t i) { return normal.dot(edge.cross(contacts[i].pointM - p0)); };
    size_t i2 = deepest, i3 = deepest;
    for (size_t i = 0; i < contacts.size(); ++i) {
        if (side(i) > side(i2)) i2 = i;
        if (side(i) < side(i3)) i3 = i;
    }
    std::vector<size_t> chosen;
    for (size_t i : {deepest, i1, i2, i3}) {
        const bool seen = std::any_of(chosen.begin(), chosen.end(), [&](size_t j) { return contacts[j].pointM == contacts[i].pointM; });
        if (!seen) chosen.push_back(i);
    }
    return chosen;
}

/// Whether the box of index coordinates `box`, mapped by u = m i + t (m a rotation), meets the
/// axis-aligned box [lo, hi]: the separating-axis test on the six face axes (without the edge
/// axes it can say yes for boxes that miss each other, which only costs a futile look).
bool boxesOverlap(const openvdb::CoordBBox& box, const Eigen::Matrix3d& m, const Eigen::Vector3d& t, const Eigen::Vector3d& lo,
                  const Eigen::Vector3d& hi)
{
    const Eigen::Vector3d boxMin(box.min().x(), box.min().y(), box.min().z()), boxMax(box.max().x(), box.max().y(), box.max().z());
    const Eigen::Vector3d half = 0.5 * (boxMax - boxMin);
    const Eigen::Vector3d offset = m * (0.5 * (boxMin + boxMax)) + t - 0.5 * (lo + hi);
    const Eigen::Vector3d otherHalf = 0.5 * (hi - lo);
    const Eigen::Matrix3d absM = m.cwiseAbs();
    if (((offset.cwiseAbs() - absM * half - otherHalf).array() > 0).any()) return false;
    return !(((m.transpose() * offset).cwiseAbs() - half - absM.transpose() * otherHalf).array() > 0).any();
}

// ---- narrow phase: spall's tree lookup -------------------------------------------------------

/// Boundary voxels of the body with fewer of them, moved into the other's index space and looked
/// up in its tree: only the few voxels around the moved centre can be within reach.
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
    const Eigen::Vector3d lo = Eigen::Vector3d(box.min().x(), box.min().y(), box.min().z()).array() - kReach;
    const Eigen::Vector3d hi = Eigen::Vector3d(box.max().x(), box.max().y(), box.max().z()).array() + kReach;
    if (!boxesOverlap(probe.indexBounds, m, t, lo, hi)) return out;  // no probe voxel can be within reach
    out.reserve(32);
    const ConstLinkAccessor targetAcc(target.grid->constTree());
    const CubePairAxes axes(a.orientation.toRotationMatrix(), b.orientation.toRotationMatrix(), h);
    constexpr double reach2 = kReach * kReach;
    VoxelContact contact;
    for (const openvdb::Coord& ijk : probe.boundaryVoxels) {
        const Eigen::Vector3d u = m * Eigen::Vector3d(ijk.x(), ijk.y(), ijk.z()) + t;
        if ((u.array() <= lo.array()).any() || (u.array() >= hi.array()).any()) continue;
        // Per axis the (at most four) lattice lines within reach and inside the target's bounds,
        // and their squared distances.
        int first[3], count[3];
        double dist2[3][4];
        for (int axis = 0; axis < 3; ++axis) {
            first[axis] = std::max(box.min()[axis], static_cast<int>(std::ceil(u[axis] - kReach)));
            count[axis] = std::min({4, box.max()[axis] - first[axis] + 1, static_cast<int>(std::floor(u[axis] + kReach)) - first[axis] + 1});
            for (int n = 0; n < count[axis]; ++n) dist2[axis][n] = (u[axis] - (first[axis] + n)) * (u[axis] - (first[axis] + n));
        }
        bool probeCentreKnown = false;
        Eigen::Vector3d probeCentre;
        for (int x = 0; x < count[0]; ++x)
            for (int y = 0; y < count[1]; ++y) {
                const double xy = dist2[0][x] + dist2[1][y];
                if (xy >= reach2) continue;
                for (int z = 0; z < count[2]; ++z) {
                    const openvdb::Coord k(first[0] + x, first[1] + y, first[2] + z);
                    if (xy + dist2[2][z] >= reach2 || !targetAcc.isValueOn(k)) continue;
                    if (!probeCentreKnown) {
                        probeCentre = probe.voxelWorldM(ijk);
                        probeCentreKnown = true;
                    }
                    const Eigen::Vector3d targetToProbe = rt * (u - Eigen::Vector3d(k.x(), k.y(), k.z())) * h;
                    const bool touching = probeIsA ? makeVoxelContact(axes, h, probeCentre, targetToProbe, contact)
                                                   : makeVoxelContact(axes, h, probeCentre - targetToProbe, -targetToProbe, contact);
                    if (touching) out.push_back(contact);
                }
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
    forEachIndex(bodies.size(), [&](size_t i) {
        for (size_t k = 0; k < bodies[i].boundaryVoxels.size(); ++k) {
            voxels[offset[i] + k] = {bodies[i].voxelWorldM(bodies[i].boundaryVoxels[k]), static_cast<int>(i)};
        }
    });
    return voxels;
}

/// Two voxels of different bodies within reach: (pair, voxel in a, voxel in b).
struct VoxelPair {
    BodyPair pair;
    uint32_t voxelA, voxelB;  ///< indices into the world voxel list
};

/// The manifolds that hold a contact (voxels within reach can still be apart as cubes).
std::vector<ContactManifold> withoutEmpty(std::vector<ContactManifold> manifolds)
{
    manifolds.erase(std::remove_if(manifolds.begin(), manifolds.end(), [](const ContactManifold& m) { return m.points.empty(); }),
                    manifolds.end());
    return manifolds;
}

/// Groups voxel pairs (already in a deterministic order) by body pair and reduces each group.
std::vector<ContactManifold> manifoldsFromVoxelPairs(const std::vector<Body>& bodies, const std::vector<WorldVoxel>& voxels,
                                                     std::vector<VoxelPair>& all)
{
    std::stable_sort(all.begin(), all.end(), [](const VoxelPair& x, const VoxelPair& y) { return x.pair < y.pair; });
    std::vector<std::pair<size_t, size_t>> groups;
    for (size_t i = 0; i < all.size();) {
        size_t j = i;
        while (j < all.size() && all[j].pair == all[i].pair) ++j;
        groups.emplace_back(i, j);
        i = j;
    }
    std::vector<ContactManifold> manifolds(groups.size());
    forEachIndex(groups.size(), [&](size_t g) {
        const Body& a = bodies[all[groups[g].first].pair.a];
        const Body& b = bodies[all[groups[g].first].pair.b];
        const CubePairAxes axes(a.orientation.toRotationMatrix(), b.orientation.toRotationMatrix(), a.voxelSizeM);
        std::vector<VoxelContact> contacts;
        VoxelContact contact;
        for (size_t k = groups[g].first; k < groups[g].second; ++k) {
            const Eigen::Vector3d& ca = voxels[all[k].voxelA].centreM;
            if (makeVoxelContact(axes, a.voxelSizeM, ca, ca - voxels[all[k].voxelB].centreM, contact)) contacts.push_back(contact);
        }
        manifolds[g] = reduceManifold(all[groups[g].first].pair.a, all[groups[g].first].pair.b, contacts, a.voxelSizeM);
    });
    return withoutEmpty(std::move(manifolds));
}

/// Runs perBlock(begin, end, out) over fixed blocks in parallel and joins the outputs in block order.
template <typename PerBlock>
std::vector<VoxelPair> collectInBlocks(size_t count, size_t blockSize, const PerBlock& perBlock)
{
    const size_t blocks = (count + blockSize - 1) / blockSize;
    std::vector<std::vector<VoxelPair>> found(blocks);
    forEachIndex(blocks, [&](size_t blk) { perBlock(blk * blockSize, std::min(count, (blk + 1) * blockSize), found[blk]); });
    std::vector<VoxelPair> all;
    for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
    return all;
}

/// Appends the pair (i, j) when the voxels belong to different bodies that can interact and lie
/// within reach; the lower body index goes first.
void testVoxelPair(const std::vector<WorldVoxel>& voxels, const std::vector<char>& moves, size_t i, size_t j, double reach2,
                   std::vector<VoxelPair>& out)
{
    const WorldVoxel& p = voxels[i];
    const WorldVoxel& q = voxels[j];
    if (p.body == q.body || (!moves[p.body] && !moves[q.body])) return;
    if ((p.centreM - q.centreM).squaredNorm() >= reach2) return;
    if (p.body < q.body)
        out.push_back({{p.body, q.body}, static_cast<uint32_t>(i), static_cast<uint32_t>(j)});
    else
        out.push_back({{q.body, p.body}, static_cast<uint32_t>(j), static_cast<uint32_t>(i)});
}

std::vector<char> movableFlags(const std::vector<Body>& bodies)
{
    std::vector<char> moves(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) moves[i] = movable(bodies[i]);
    return moves;
}

/// The paper's first scheme: every boundary voxel against every boundary voxel of other bodies.
std::vector<ContactManifold> pairwiseContacts(const std::vector<Body>& bodies)
{
    const std::vector<WorldVoxel> voxels = worldBoundaryVoxels(bodies);
    if (voxels.empty()) return {};
    const double h = bodies.front().voxelSizeM;
    const std::vector<char> moves = movableFlags(bodies);
    std::vector<VoxelPair> all = collectInBlocks(voxels.size(), 256, [&](size_t begin, size_t end, std::vector<VoxelPair>& out) {
        for (size_t i = begin; i < end; ++i)
            for (size_t j = i + 1; j < voxels.size(); ++j) testVoxelPair(voxels, moves, i, j, kReach * kReach * h * h, out);
    });
    return manifoldsFromVoxelPairs(bodies, voxels, all);
}

/// The paper's second scheme: boundary voxels sorted into buckets as wide as the contact reach;
/// each voxel is tested against the voxels of its own and the 26 adjacent buckets.
std::vector<ContactManifold> bucketContacts(const std::vector<Body>& bodies)
{
    const std::vector<WorldVoxel> voxels = worldBoundaryVoxels(bodies);
    if (voxels.empty()) return {};
    const double h = bodies.front().voxelSizeM;
    const double bucket = kReach * h;
    auto cellOf = [&](const Eigen::Vector3d& x) {
        return openvdb::Coord(static_cast<int>(std::floor(x.x() / bucket)), static_cast<int>(std::floor(x.y() / bucket)),
                              static_cast<int>(std::floor(x.z() / bucket)));
    };
    auto key = [](const openvdb::Coord& c) {
        // 21 bits per axis: buckets one voxel wide over +-10^6 voxels.
        return (uint64_t(uint32_t(c.x()) & 0x1fffff) << 42) | (uint64_t(uint32_t(c.y()) & 0x1fffff) << 21) | uint64_t(uint32_t(c.z()) & 0x1fffff);
    };
    std::vector<std::pair<uint64_t, uint32_t>> table(voxels.size());
    for (size_t i = 0; i < voxels.size(); ++i) table[i] = {key(cellOf(voxels[i].centreM)), static_cast<uint32_t>(i)};
    std::sort(table.begin(), table.end());
    const std::vector<char> moves = movableFlags(bodies);
    std::vector<VoxelPair> all = collectInBlocks(voxels.size(), 1024, [&](size_t begin, size_t end, std::vector<VoxelPair>& out) {
        for (size_t i = begin; i < end; ++i) {
            const openvdb::Coord cell = cellOf(voxels[i].centreM);
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const uint64_t k = key(cell.offsetBy(dx, dy, dz));
                        auto it = std::lower_bound(table.begin(), table.end(), std::make_pair(k, uint32_t(0)));
                        for (; it != table.end() && it->first == k; ++it)
                            if (it->second > i) testVoxelPair(voxels, moves, i, it->second, kReach * kReach * h * h, out);
                    }
        }
    });
    return manifoldsFromVoxelPairs(bodies, voxels, all);
}

// ---- contacts with the ground and static boxes -----------------------------------------------

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
    const double margin = kContactMarginVoxels * h;
    const double voxelRadius = 0.5 * std::sqrt(3.0) * h + margin;
    const GroundPlane& ground = world.ground;
    const bool nearGround = ground.enabled && ground.normal.dot(body.positionM) - ground.offsetM <= body.boundingRadiusM + margin;
    std::vector<int> nearBoxes;
    for (size_t b = 0; b < world.colliders.size(); ++b) {
        const StaticBox& box = world.colliders[b];
        const Eigen::Vector3d local = box.orientation.inverse() * (body.positionM - box.centreM);
        const Eigen::Vector3d outside = (local.cwiseAbs() - box.halfExtentM).cwiseMax(0.0);
        if (outside.norm() <= body.boundingRadiusM + margin) nearBoxes.push_back(static_cast<int>(b));
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
                if (separation < margin)
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
                if ((penetration.array() <= -margin).any() || (penetration.array() <= 0.0).count() > 1) return;
                int axis = 0;
                penetration.minCoeff(&axis);
                const Eigen::Vector3d normal = boxRot.col(axis) * (q[axis] >= 0 ? 1.0 : -1.0);
                contacts.push_back({centreArm + corner, normal, penetration[axis], b, box.restitution, box.friction});
            });
        }
    }
    return contacts;
}

/// Per collider and normal, the corners reduced to at most four spanning points.
std::vector<StaticContact> reduceStaticContacts(const std::vector<StaticContact>& all)
{
    std::vector<StaticContact> reduced;
    std::vector<char> done(all.size(), 0);
    for (size_t i = 0; i < all.size(); ++i) {
        if (done[i]) continue;
        std::vector<size_t> group;
        std::vector<VoxelContact> points;
        size_t deepest = 0;
        for (size_t j = i; j < all.size(); ++j)
            if (!done[j] && all[j].collider == all[i].collider && all[j].normal == all[i].normal) {
                done[j] = 1;
                if (all[j].depth > all[group.empty() ? j : group[deepest]].depth) deepest = group.size();
                group.push_back(j);
                points.push_back({all[j].arm, all[j].normal, all[j].depth});
            }
        for (size_t k : spanningPoints(points, all[i].normal, deepest)) reduced.push_back(all[group[k]]);
    }
    return reduced;
}

struct SolverBody {
    Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
    double invMass = 0;
    Eigen::Matrix3d invInertia = Eigen::Matrix3d::Zero();
};

/// Removes penetration by moving positions only (velocities untouched: no kinetic energy is
/// added). Constraints: per body and static collider its deepest contact, per touching pair its
/// manifold, split by inverse mass; a few Gauss–Seidel passes from the bottom up, each seeing
/// the depth that earlier moves left. `state` ends with the world's immovable entry.
void correctPositions(std::vector<Body>& bodies, const std::vector<SolverBody>& state,
                      const std::vector<std::vector<StaticContact>>& statics, const std::vector<ContactManifold>& manifolds,
                      const Eigen::Vector3d& up, size_t colliderCount)
{
    if (bodies.empty()) return;
    struct Constraint {
        int a, b;  ///< indices into `state`; its last entry is the immovable world
        Eigen::Vector3d normal;
        double depth, height;
    };
    const int worldIndex = static_cast<int>(state.size()) - 1;
    std::vector<Constraint> constraints;
    for (size_t i = 0; i < bodies.size(); ++i) {
        for (int collider = -1; collider < static_cast<int>(colliderCount); ++collider) {
            const StaticContact* deepest = nullptr;
            for (const StaticContact& c : statics[i])
                if (c.collider == collider && (!deepest || c.depth > deepest->depth)) deepest = &c;
            if (deepest)
                constraints.push_back({static_cast<int>(i), worldIndex, deepest->normal, deepest->depth, up.dot(bodies[i].positionM)});
        }
    }
    for (const ContactManifold& m : manifolds)
        if (state[m.a].invMass + state[m.b].invMass > 0)
            constraints.push_back({m.a, m.b, m.normal, m.maxDepthM, up.dot(bodies[m.a].positionM + bodies[m.b].positionM) / 2});
    std::stable_sort(constraints.begin(), constraints.end(), [](const Constraint& x, const Constraint& y) { return x.height < y.height; });
    const double slop = 0.01 * bodies.front().voxelSizeM;
    std::vector<Eigen::Vector3d> shift(state.size(), Eigen::Vector3d::Zero());
    for (int pass = 0; pass < 4; ++pass) {
        for (const Constraint& c : constraints) {
            const double depth = c.depth - c.normal.dot(shift[c.a] - shift[c.b]);
            if (depth <= slop) continue;
            const double ia = state[c.a].invMass, ib = state[c.b].invMass;
            shift[c.a] += (depth - slop) * ia / (ia + ib) * c.normal;
            shift[c.b] -= (depth - slop) * ib / (ia + ib) * c.normal;
        }
    }
    for (size_t i = 0; i < bodies.size(); ++i) bodies[i].positionM += shift[i];
}

/// Rest times per body, then islands of touching bodies (anchored bodies join none) by union-find;
/// an island sleeps when all its awake bodies have rested long enough. Sleeping body by body
/// instead lets settling neighbours knock each other awake again and again.
void putRestingIslandsToSleep(std::vector<Body>& bodies, const std::vector<BodyPair>& touching, const std::vector<char>& loaded,
                              const SleepSettings& sleep, double dt)
{
    for (size_t i = 0; i < bodies.size(); ++i) {
        Body& b = bodies[i];
        if (b.anchored || b.asleep) continue;
        b.restTimeS = (!loaded[i] && maxVoxelSpeedMS(b) < sleep.speedMS) ? b.restTimeS + dt : 0.0;
    }
    std::vector<int> parent(bodies.size());
    for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
    auto root = [&](int i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    for (const BodyPair& p : touching)
        if (!bodies[p.a].anchored && !bodies[p.b].anchored) {
            const int ra = root(p.a), rb = root(p.b);
            parent[std::max(ra, rb)] = std::min(ra, rb);
        }
    std::vector<char> restless(bodies.size(), 0);
    for (size_t i = 0; i < bodies.size(); ++i)
        if (!bodies[i].anchored && !bodies[i].asleep && bodies[i].restTimeS < sleep.timeS) restless[root(static_cast<int>(i))] = 1;
    for (size_t i = 0; i < bodies.size(); ++i) {
        Body& b = bodies[i];
        if (b.anchored || b.asleep || restless[root(static_cast<int>(i))]) continue;
        b.asleep = true;
        b.linearVelocityMS.setZero();
        b.angularVelocityRadS.setZero();
    }
}

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
        if (movable(bodies[i])) xs.push_back({bodies[i].positionM.x(), static_cast<int>(i)});
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

}  // namespace

bool pairCanInteract(const Body& a, const Body& b) { return movable(a) || movable(b); }

std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies)
{
    if (bodies.empty()) return {};
    // A hierarchical grid: level k has cells base * 2^k wide, and a body lives at the finest
    // level whose cells are at least its bounding diameter, in the cell of its centre. Two
    // overlapping spheres are then at most one cell apart on the coarser one's level, so each
    // occupied cell looks in the 27 cells around it on its own level and around its parent on
    // every coarser occupied level.
    // Work follows the bodies and their neighbours, whatever their sizes and however densely
    // packed (a sweep along one axis grows as n^(5/3) in a packed 3-D cloud).
    double smallest = std::numeric_limits<double>::infinity();
    for (const Body& b : bodies) smallest = std::min(smallest, b.boundingRadiusM);
    const double base = 2.0 * std::max(smallest, 1e-9);
    auto levelOf = [&](double radius) {
        int level = 0;
        while (base * std::ldexp(1.0, level) < 2.0 * radius && level < 60) ++level;
        return level;
    };
    struct Cell {
        int level;
        int64_t z, y, x;
        bool operator<(const Cell& o) const { return std::tie(level, z, y, x) < std::tie(o.level, o.z, o.y, o.x); }
    };
    auto cellAt = [&](const Eigen::Vector3d& p, int level) {
        const double size = base * std::ldexp(1.0, level);
        return Cell{level, static_cast<int64_t>(std::floor(p.z() / size)), static_cast<int64_t>(std::floor(p.y() / size)),
                    static_cast<int64_t>(std::floor(p.x() / size))};
    };
    std::vector<std::pair<Cell, int>> entries(bodies.size());
    forEachIndex(bodies.size(), [&](size_t i) {
        entries[i] = {cellAt(bodies[i].positionM, levelOf(bodies[i].boundingRadiusM)), static_cast<int>(i)};
    }, kCheapGrain);
    std::sort(entries.begin(), entries.end(),
              [](const auto& x, const auto& y) { return x.first < y.first || (!(y.first < x.first) && x.second < y.second); });
    // Occupied cells as runs of entries; the bodies of one cell share every search.
    struct Run {
        Cell cell;
        size_t begin, end;
    };
    std::vector<Run> runs;
    for (size_t k = 0; k < entries.size(); ++k) {
        if (runs.empty() || runs.back().cell < entries[k].first) runs.push_back({entries[k].first, k, k});
        runs.back().end = k + 1;
    }
    std::vector<int> levels;
    for (const Run& r : runs)
        if (levels.empty() || levels.back() != r.cell.level) levels.push_back(r.cell.level);
    auto floorHalf = [](int64_t v, int shift) { return v >= 0 ? v >> shift : -((-v + (int64_t(1) << shift) - 1) >> shift); };
    constexpr size_t kBlock = 64;
    std::vector<std::vector<BodyPair>> found((runs.size() + kBlock - 1) / kBlock);
    forEachIndex(found.size(), [&](size_t block) {
        auto test = [&](int i, int j) {
            const Body& a = bodies[i];
            const Body& b = bodies[j];
            const double reach = a.boundingRadiusM + b.boundingRadiusM;
            if ((a.positionM - b.positionM).squaredNorm() > reach * reach || !pairCanInteract(a, b)) return;
            found[block].push_back({std::min(i, j), std::max(i, j)});
        };
        for (size_t r = block * kBlock; r < std::min(runs.size(), (block + 1) * kBlock); ++r) {
            const Run& run = runs[r];
            for (size_t p = run.begin; p < run.end; ++p)
                for (size_t q = p + 1; q < run.end; ++q) test(entries[p].second, entries[q].second);
            for (int l : levels) {
                if (l < run.cell.level) continue;
                // This cell's cell on level l (cells nest: each is half its parent's width).
                const int shift = l - run.cell.level;
                const Cell centre{l, floorHalf(run.cell.z, shift), floorHalf(run.cell.y, shift), floorHalf(run.cell.x, shift)};
                for (int64_t dz = -1; dz <= 1; ++dz)
                    for (int64_t dy = -1; dy <= 1; ++dy) {
                        // Cells (z, y, x - 1 .. x + 1) are contiguous among the runs.
                        const Cell first{l, centre.z + dz, centre.y + dy, centre.x - 1};
                        auto it = std::lower_bound(runs.begin(), runs.end(), first, [](const Run& x, const Cell& c) { return x.cell < c; });
                        for (; it != runs.end() && it->cell.level == l && it->cell.z == first.z && it->cell.y == first.y &&
                               it->cell.x <= centre.x + 1;
                             ++it) {
                            // On its own level each pair of cells once, from the lower; a coarser
                            // cell never looks down, so the finer one reports the pair.
                            if (shift == 0 && !(run.cell < it->cell)) continue;
                            for (size_t p = run.begin; p < run.end; ++p)
                                for (size_t q = it->begin; q < it->end; ++q) test(entries[p].second, entries[q].second);
                        }
                    }
            }
        }
    });
    std::vector<BodyPair> pairs;
    for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
    tbb::parallel_sort(pairs.begin(), pairs.end());  // pairs are unique: the order is
    return pairs;
}

ContactManifold reduceManifold(int a, int b, const std::vector<VoxelContact>& contacts, double voxelSizeM)
{
    ContactManifold m;
    m.a = a;
    m.b = b;
    m.voxelContacts = static_cast<int64_t>(contacts.size());
    if (contacts.empty()) return m;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    size_t deepest = 0;
    for (size_t i = 0; i < contacts.size(); ++i) {
        // Weight by how far inside the reach the pair is (depth may be negative: a gap).
        sum += (contacts[i].depthM + kContactMarginVoxels * voxelSizeM) * contacts[i].normal;
        if (contacts[i].depthM > contacts[deepest].depthM) deepest = i;
    }
    m.maxDepthM = contacts[deepest].depthM;
    m.normal = sum.norm() > 1e-12 * voxelSizeM ? Eigen::Vector3d(sum.normalized()) : contacts[deepest].normal;
    for (size_t i : spanningPoints(contacts, m.normal, deepest)) m.points.push_back(contacts[i]);
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
    forEachIndex(pairs.size(), [&](size_t i) {
        found[i] = reduceManifold(pairs[i].a, pairs[i].b, treeLookupContacts(bodies[pairs[i].a], bodies[pairs[i].b]),
                                  bodies[pairs[i].a].voxelSizeM);
    });
    return withoutEmpty(std::move(found));
}

ContactStats resolveContacts(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                             const SleepSettings& sleep, double dt, ContactCache* cache)
{
    ContactStats stats;
    const std::vector<ContactManifold> manifolds = findBodyContacts(bodies, collisions.method);
    // A moving body wakes a sleeping one it hits; a resting one leaves it asleep (and static).
    for (const ContactManifold& m : manifolds) {
        Body& a = bodies[m.a];
        Body& b = bodies[m.b];
        auto wakes = [&](const Body& mover) { return movable(mover) && maxVoxelSpeedMS(mover) > sleep.speedMS; };
        for (auto [sleeper, other] : {std::pair<Body*, Body*>{&a, &b}, std::pair<Body*, Body*>{&b, &a}})
            if (sleeper->asleep && !sleeper->anchored && wakes(*other)) {
                sleeper->asleep = false;
                sleeper->restTimeS = 0;
            }
    }

    std::vector<std::vector<StaticContact>> statics(bodies.size());
    forEachIndex(bodies.size(), [&](size_t i) {
        if (movable(bodies[i])) statics[i] = reduceStaticContacts(findStaticContacts(bodies[i], world));
    });

    // Solver state per body; the world (ground and boxes) is one extra, immovable entry.
    const int worldIndex = static_cast<int>(bodies.size());
    std::vector<SolverBody> state(bodies.size() + 1);
    std::vector<Eigen::Matrix3d> rotation(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
        const Body& body = bodies[i];
        rotation[i] = body.orientation.toRotationMatrix();
        if (!movable(body)) continue;
        state[i] = {body.linearVelocityMS, body.angularVelocityRadS, 1.0 / body.mass.massKg,
                    rotation[i] * body.mass.inertiaKgM2.inverse() * rotation[i].transpose()};
    }
    auto velocityAt = [&](int i, const Eigen::Vector3d& arm) -> Eigen::Vector3d { return state[i].v + state[i].w.cross(arm); };
    // Bounce only above the speed gravity adds in a couple of steps, so resting contacts rest.
    const double bounceThreshold = 2.0 * world.gravityMS2.norm() * dt + 0.05;
    const Eigen::Vector3d up = world.gravityMS2.squaredNorm() > 0 ? Eigen::Vector3d(-world.gravityMS2.normalized()) : world.ground.normal;
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
        c.height = up.dot(bodies[a].positionM + armA);
        return c;
    };
    // Static contacts body by body, then the manifolds' points; each source fills its own slots.
    std::vector<size_t> staticStart(bodies.size() + 1, 0), manifoldStart(manifolds.size() + 1, 0);
    for (size_t i = 0; i < bodies.size(); ++i) staticStart[i + 1] = staticStart[i] + statics[i].size();
    manifoldStart[0] = staticStart.back();
    for (size_t m = 0; m < manifolds.size(); ++m) {
        manifoldStart[m + 1] = manifoldStart[m] + manifolds[m].points.size();
        stats.bodyContacts += manifolds[m].voxelContacts;
        stats.maxPenetrationM = std::max(stats.maxPenetrationM, manifolds[m].maxDepthM);
        stats.touching.push_back({manifolds[m].a, manifolds[m].b});
    }
    stats.staticContacts = static_cast<int64_t>(staticStart.back());
    stats.solverContacts = static_cast<int64_t>(manifoldStart.back());
    std::vector<SolverContact> contacts(manifoldStart.back());
    forEachIndex(bodies.size(), [&](size_t i) {
        for (size_t n = 0; n < statics[i].size(); ++n) {
            const StaticContact& s = statics[i][n];
            contacts[staticStart[i] + n] = makeContact(static_cast<int>(i), worldIndex, {bodies[i].id, -2 - s.collider}, s.arm,
                                                       Eigen::Vector3d::Zero(), s.normal, s.depth, s.restitution, s.friction);
        }
    }, kCheapGrain);
    forEachIndex(manifolds.size(), [&](size_t m) {
        const ContactManifold& manifold = manifolds[m];
        const Body& a = bodies[manifold.a];
        const Body& b = bodies[manifold.b];
        for (size_t n = 0; n < manifold.points.size(); ++n) {
            const VoxelContact& p = manifold.points[n];
            contacts[manifoldStart[m] + n] = makeContact(manifold.a, manifold.b, {a.id, b.id}, p.pointM - a.positionM, p.pointM - b.positionM,
                                                         manifold.normal, p.depthM, collisions.restitution, collisions.friction);
        }
    }, kCheapGrain);
    if (contacts.empty()) {
        if (cache) cache->points.clear();
        return stats;
    }
    ImpulseSolver solver(bodies, state, contacts);
    if (cache) solver.warmStart(*cache, bodies, rotation);
    solver.solve(collisions.solverIterations);
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (!movable(bodies[i])) continue;
        bodies[i].linearVelocityMS = state[i].v;
        bodies[i].angularVelocityRadS = state[i].w;
    }
    if (cache) solver.store(*cache, rotation);
    correctPositions(bodies, state, statics, manifolds, up, world.colliders.size());
    return stats;
}

ContactStats stepBodies(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                        const SleepSettings& sleep, Integrator integrator, double timeS, double dt, ContactCache* cache,
                        const ExternalLoad* load)
{
    std::vector<char> loaded(bodies.size(), 0);
    // Bodies are independent here: each task writes only its own body.
    forEachIndex(bodies.size(), [&](size_t i) {
        Body& body = bodies[i];
        if (body.anchored) return;
        loaded[i] = load && load->loaded(body);
        if (loaded[i]) {
            body.asleep = false;
            body.restTimeS = 0;
        }
        if (body.asleep) return;
        const double m = body.mass.massKg;
        auto wrench = [&](double t, const Eigen::Vector3d& x, const Eigen::Quaterniond& q, const Eigen::Vector3d& v,
                          const Eigen::Vector3d& w) {
            Wrench total = loaded[i] ? load->wrench(body, t, x, q) : Wrench();
            total.forceN += m * world.gravityMS2 - world.linearDragPerS * m * v;
            const Eigen::Matrix3d r = q.toRotationMatrix();
            total.torqueNm -= world.angularDragPerS * (r * body.mass.inertiaKgM2 * r.transpose() * w);
            return total;
        };
        integrateBody(body, timeS, dt, integrator, wrench);
    });
    const ContactStats stats = resolveContacts(bodies, world, collisions, sleep, dt, cache);
    if (sleep.enabled) putRestingIslandsToSleep(bodies, stats.touching, loaded, sleep, dt);
    return stats;
}

}  // namespace spall
