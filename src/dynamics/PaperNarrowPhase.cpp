// The paper's narrow phases (section 4.2), kept as baselines: every boundary voxel against every
// other, and buckets (a spatial hash of boundary voxels).
#include "VoxelContact.h"

#include <spall/core/Parallel.h>
#include <spall/dynamics/BroadPhase.h>
#include <spall/dynamics/Integrate.h>

#include <algorithm>
#include <cmath>

namespace spall::narrow {

namespace {

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
        const CubePairAxes axes(a.motion.orientation.toRotationMatrix(), b.motion.orientation.toRotationMatrix(), a.voxelSizeM);
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
void testVoxelPair(const std::vector<WorldVoxel>& voxels, const std::vector<Body>& bodies, size_t i, size_t j, double reach2,
                   std::vector<VoxelPair>& out)
{
    const WorldVoxel& p = voxels[i];
    const WorldVoxel& q = voxels[j];
    if (p.body == q.body || !pairCanInteract(bodies[p.body], bodies[q.body])) return;
    if ((p.centreM - q.centreM).squaredNorm() >= reach2) return;
    if (p.body < q.body)
        out.push_back({{p.body, q.body}, static_cast<uint32_t>(i), static_cast<uint32_t>(j)});
    else
        out.push_back({{q.body, p.body}, static_cast<uint32_t>(j), static_cast<uint32_t>(i)});
}

}  // namespace

std::vector<ContactManifold> pairwiseContacts(const std::vector<Body>& bodies)
{
    const std::vector<WorldVoxel> voxels = worldBoundaryVoxels(bodies);
    if (voxels.empty()) return {};
    const double h = bodies.front().voxelSizeM;
    std::vector<VoxelPair> all = collectInBlocks(voxels.size(), 256, [&](size_t begin, size_t end, std::vector<VoxelPair>& out) {
        for (size_t i = begin; i < end; ++i)
            for (size_t j = i + 1; j < voxels.size(); ++j) testVoxelPair(voxels, bodies, i, j, kReach * kReach * h * h, out);
    });
    return manifoldsFromVoxelPairs(bodies, voxels, all);
}

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
    std::vector<VoxelPair> all = collectInBlocks(voxels.size(), 1024, [&](size_t begin, size_t end, std::vector<VoxelPair>& out) {
        for (size_t i = begin; i < end; ++i) {
            const openvdb::Coord cell = cellOf(voxels[i].centreM);
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const uint64_t k = key(cell.offsetBy(dx, dy, dz));
                        auto it = std::lower_bound(table.begin(), table.end(), std::make_pair(k, uint32_t(0)));
                        for (; it != table.end() && it->first == k; ++it)
                            if (it->second > i) testVoxelPair(voxels, bodies, i, it->second, kReach * kReach * h * h, out);
                    }
        }
    });
    return manifoldsFromVoxelPairs(bodies, voxels, all);
}

}  // namespace spall::narrow
