// Groups of indices joined pair by pair (union-find with path halving). Each group's root is its
// lowest index, so the groups and their roots do not depend on the order of the joins.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace spall {

class DisjointSets {
public:
    explicit DisjointSets(size_t count) : mParent(count) { std::iota(mParent.begin(), mParent.end(), 0u); }

    uint32_t root(uint32_t i)
    {
        while (mParent[i] != i) i = mParent[i] = mParent[mParent[i]];
        return i;
    }

    void join(uint32_t a, uint32_t b)
    {
        const uint32_t ra = root(a), rb = root(b);
        mParent[std::max(ra, rb)] = std::min(ra, rb);
    }

private:
    std::vector<uint32_t> mParent;
};

}  // namespace spall
