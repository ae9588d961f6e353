#include <spall/voxel/Components.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <unordered_map>

namespace spall {

namespace {

constexpr uint32_t kSlotsPerLeaf = LinkLeaf::SIZE;  // 512
constexpr uint32_t kNone = ComponentLabels::kNoLabel;

// Union-find whose root is always the smallest slot of its set: the result is then independent
// of the order in which unions happen, which keeps labels identical for any thread count.
inline uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];  // path halving
        i = parent[i];
    }
    return i;
}

inline void unite(std::vector<uint32_t>& parent, uint32_t a, uint32_t b)
{
    a = findRoot(parent, a);
    b = findRoot(parent, b);
    if (a == b) return;
    if (a < b)
        parent[b] = a;
    else
        parent[a] = b;
}

}  // namespace

namespace {

using Slots = std::vector<uint32_t>;  ///< union-find parent per slot (leafIndex * 512 + offset)
using NeighbourLeaves = std::vector<std::array<uint32_t, 3>>;  ///< per leaf: its +x, +y, +z neighbour (kNone: absent)

/// Pass 1 (parallel, each task touches only its own leaf's slots): unions inside a leaf, and the
/// neighbour leaves. Offsets are x*64 + y*8 + z, so +x, +y, +z neighbours are +64, +8, +1.
NeighbourLeaves uniteInsideLeaves(const LinkTree& tree, const std::vector<const LinkLeaf*>& leaves, Slots& parent)
{
    std::unordered_map<const LinkLeaf*, uint32_t> leafIndex;
    leafIndex.reserve(leaves.size() * 2);
    for (size_t n = 0; n < leaves.size(); ++n) leafIndex.emplace(leaves[n], static_cast<uint32_t>(n));
    NeighbourLeaves nextLeaf(leaves.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t n = r.begin(); n != r.end(); ++n) {
            const LinkLeaf& leaf = *leaves[n];
            const uint32_t base = static_cast<uint32_t>(n) * kSlotsPerLeaf;
            for (auto it = leaf.cbeginValueOn(); it; ++it) parent[base + it.pos()] = base + it.pos();
            for (auto it = leaf.cbeginValueOn(); it; ++it) {
                const uint32_t off = static_cast<uint32_t>(it.pos());
                const int32_t bits = it.getValue();
                if ((bits & (1 << kPosX)) && (off >> 6) < 7) unite(parent, base + off, base + off + 64);
                if ((bits & (1 << kPosY)) && ((off >> 3) & 7) < 7) unite(parent, base + off, base + off + 8);
                if ((bits & (1 << kPosZ)) && (off & 7) < 7) unite(parent, base + off, base + off + 1);
            }
            for (int axis = 0; axis < 3; ++axis) {
                openvdb::Coord o = leaf.origin();
                o[axis] += LinkLeaf::DIM;
                const LinkLeaf* next = tree.probeConstLeaf(o);
                nextLeaf[n][axis] = next ? leafIndex.at(next) : kNone;
            }
        }
    });
    return nextLeaf;
}

/// Pass 2 (serial): links that cross into the +x, +y, +z neighbour leaf.
void uniteAcrossLeaves(const std::vector<const LinkLeaf*>& leaves, const NeighbourLeaves& nextLeaf, Slots& parent)
{
    for (size_t n = 0; n < leaves.size(); ++n) {
        const uint32_t base = static_cast<uint32_t>(n) * kSlotsPerLeaf;
        for (auto it = leaves[n]->cbeginValueOn(); it; ++it) {
            const uint32_t off = static_cast<uint32_t>(it.pos());
            const int32_t bits = it.getValue();
            const uint32_t x = off >> 6, y = (off >> 3) & 7, z = off & 7;
            if ((bits & (1 << kPosX)) && x == 7 && nextLeaf[n][0] != kNone)
                unite(parent, base + off, nextLeaf[n][0] * kSlotsPerLeaf + (off - 7 * 64));
            if ((bits & (1 << kPosY)) && y == 7 && nextLeaf[n][1] != kNone)
                unite(parent, base + off, nextLeaf[n][1] * kSlotsPerLeaf + (off - 7 * 8));
            if ((bits & (1 << kPosZ)) && z == 7 && nextLeaf[n][2] != kNone)
                unite(parent, base + off, nextLeaf[n][2] * kSlotsPerLeaf + (off - 7));
        }
    }
}

/// Pass 3: a root is its component's first slot, so numbering roots in slot order gives labels
/// in order of first appearance.
void numberComponents(const Slots& parent, size_t leafCount, ComponentLabels& result)
{
    std::vector<uint32_t> labelOfRoot(parent.size(), kNone);
    uint32_t count = 0;
    for (uint32_t i = 0; i < parent.size(); ++i) {
        if (parent[i] == i) labelOfRoot[i] = count++;
    }
    result.componentCount = count;
    result.labelOfSlot.assign(parent.size(), kNone);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leafCount), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t n = r.begin(); n != r.end(); ++n) {
            const uint32_t base = static_cast<uint32_t>(n) * kSlotsPerLeaf;
            for (uint32_t s = base; s < base + kSlotsPerLeaf; ++s) {
                if (parent[s] == kNone) continue;
                uint32_t root = s;
                while (parent[root] != root) root = parent[root];  // read-only: no compression here
                result.labelOfSlot[s] = labelOfRoot[root];
            }
        }
    });
}

}  // namespace

ComponentLabels labelComponents(const LinkGrid& grid)
{
    ComponentLabels result;
    openvdb::tree::LeafManager<const LinkTree> manager(grid.constTree());
    const size_t leafCount = manager.leafCount();
    result.leaves.resize(leafCount);
    for (size_t n = 0; n < leafCount; ++n) result.leaves[n] = &manager.leaf(n);
    if (leafCount == 0) return result;
    Slots parent(leafCount * kSlotsPerLeaf, kNone);
    const NeighbourLeaves nextLeaf = uniteInsideLeaves(grid.constTree(), result.leaves, parent);
    uniteAcrossLeaves(result.leaves, nextLeaf, parent);
    numberComponents(parent, leafCount, result);
    return result;
}

std::vector<LinkGrid::Ptr> splitByLabels(const LinkGrid& grid, const ComponentLabels& labels)
{
    std::vector<LinkGrid::Ptr> parts(labels.componentCount);
    for (auto& p : parts) {
        p = LinkGrid::create(grid.background());
        p->setTransform(grid.transform().copy());
        p->insertMeta(grid);
        p->setName(grid.getName());
    }
    for (size_t n = 0; n < labels.leaves.size(); ++n) {
        const LinkLeaf& leaf = *labels.leaves[n];
        const size_t base = n * kSlotsPerLeaf;
        LinkLeaf* last = nullptr;
        uint32_t lastLabel = kNone;
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const uint32_t label = labels.labelOfSlot[base + it.pos()];
            if (label != lastLabel) {
                last = parts[label]->tree().touchLeaf(leaf.origin());
                lastLabel = label;
            }
            last->setValueOn(it.pos(), it.getValue());
        }
    }
    return parts;
}

}  // namespace spall
