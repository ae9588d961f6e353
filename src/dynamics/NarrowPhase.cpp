#include <spall/dynamics/NarrowPhase.h>

#include "VoxelContact.h"

#include <spall/core/Parallel.h>
#include <spall/dynamics/BroadPhase.h>

#include <algorithm>
#include <cmath>

namespace spall {

namespace narrow {

std::vector<ContactManifold> withoutEmpty(std::vector<ContactManifold> manifolds)
{
    manifolds.erase(std::remove_if(manifolds.begin(), manifolds.end(), [](const ContactManifold& m) { return m.points.empty(); }),
                    manifolds.end());
    return manifolds;
}

}  // namespace narrow

using namespace narrow;

namespace {

/// Not registered with the tree (registration costs a locked hash-map insert per pair).
using ConstLinkAccessor = openvdb::tree::ValueAccessor<const LinkTree, false>;

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
/// up in its tree: only the few voxels around the moved centre can be within reach. Into `out`
/// (emptied first).
void treeLookupContacts(const Body& a, const Body& b, std::vector<VoxelContact>& out)
{
    out.clear();
    const bool probeIsA = a.boundaryVoxels.size() <= b.boundaryVoxels.size();
    const Body& probe = probeIsA ? a : b;
    const Body& target = probeIsA ? b : a;
    const double h = target.voxelSizeM;
    const Eigen::Matrix3d rp = probe.motion.orientation.toRotationMatrix();
    const Eigen::Matrix3d rt = target.motion.orientation.toRotationMatrix();
    // target index u = M i + t for probe index i (both bodies share the scene's voxel size).
    const Eigen::Matrix3d m = rt.transpose() * rp * (probe.voxelSizeM / h);
    const Eigen::Vector3d t =
        (rt.transpose() * (probe.motion.positionM - target.motion.positionM - rp * probe.mass.centreOfMassLocalM) + target.mass.centreOfMassLocalM) / h;
    const openvdb::CoordBBox& box = target.indexBounds;
    const Eigen::Vector3d lo = Eigen::Vector3d(box.min().x(), box.min().y(), box.min().z()).array() - kReach;
    const Eigen::Vector3d hi = Eigen::Vector3d(box.max().x(), box.max().y(), box.max().z()).array() + kReach;
    if (!boxesOverlap(probe.indexBounds, m, t, lo, hi)) return;  // no probe voxel can be within reach
    const ConstLinkAccessor targetAcc(target.grid->constTree());
    const CubePairAxes axes(a.motion.orientation.toRotationMatrix(), b.motion.orientation.toRotationMatrix(), h);
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
}

}  // namespace

// A quadrilateral spanning the patch resists tipping as well as all of them,
// and fewer, distinct points let the solver converge faster.
std::vector<size_t> spanningPoints(const std::vector<VoxelContact>& contacts, const Eigen::Vector3d& normal)
{
    if (contacts.size() <= 4) {
        std::vector<size_t> all(contacts.size());
        for (size_t i = 0; i < all.size(); ++i) all[i] = i;
        return all;
    }
    // Start from the patch's extreme along a fixed oblique tangent, a corner, not from its deepest
    // point: depths across a resting patch differ by rounding, so the deepest jumps across it
    // from step to step, the points with it, and the warm start (which matches points within a
    // quarter voxel) lost the impulses; a heavy slab on a jagged patch then rocked by millimetres.
    const Eigen::Vector3d oblique(0.3713, 0.8122, 0.4498);
    const Eigen::Vector3d tangent = oblique - oblique.dot(normal) * normal;
    size_t first = 0;
    for (size_t i = 1; i < contacts.size(); ++i)
        if (contacts[i].pointM.dot(tangent) < contacts[first].pointM.dot(tangent)) first = i;
    const Eigen::Vector3d p0 = contacts[first].pointM;
    size_t i1 = first;
    for (size_t i = 0; i < contacts.size(); ++i)
        if ((contacts[i].pointM - p0).squaredNorm() > (contacts[i1].pointM - p0).squaredNorm()) i1 = i;
    const Eigen::Vector3d edge = contacts[i1].pointM - p0;
    auto side = [&](size_t i) { return normal.dot(edge.cross(contacts[i].pointM - p0)); };
    size_t i2 = first, i3 = first;
    for (size_t i = 0; i < contacts.size(); ++i) {
        if (side(i) > side(i2)) i2 = i;
        if (side(i) < side(i3)) i3 = i;
    }
    std::vector<size_t> chosen;
    for (size_t i : {first, i1, i2, i3}) {
        const bool seen = std::any_of(chosen.begin(), chosen.end(), [&](size_t j) { return contacts[j].pointM == contacts[i].pointM; });
        if (!seen) chosen.push_back(i);
    }
    return chosen;
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
    for (size_t i : spanningPoints(contacts, m.normal)) m.points.push_back(contacts[i]);
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
        // Two slabs lying on each other touch at ~10^5 voxel pairs: the list is kept per thread
        // (as findStaticContacts' corners).
        thread_local std::vector<VoxelContact> contacts;
        treeLookupContacts(bodies[pairs[i].a], bodies[pairs[i].b], contacts);
        found[i] = reduceManifold(pairs[i].a, pairs[i].b, contacts, bodies[pairs[i].a].voxelSizeM);
    });
    return withoutEmpty(std::move(found));
}

}  // namespace spall
