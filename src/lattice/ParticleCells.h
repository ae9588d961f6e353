// Particles sorted into the cells of a grid, for listing the pairs close enough to touch
// (LatticeContact.cpp within a lattice, LatticePairContact.cpp between two).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace spall {

class ParticleCells {
public:
    using Cell = std::array<int64_t, 3>;

    /// The particles `members` (indices into `placesM`) in cells of side `cellM`.
    ParticleCells(const std::vector<Eigen::Vector3d>& placesM, const std::vector<uint32_t>& members, double cellM) : mCellM(cellM)
    {
        mByCell.reserve(members.size());
        for (const uint32_t p : members) mByCell.emplace_back(keyOf(cellOf(placesM[p])), p);
        std::sort(mByCell.begin(), mByCell.end());
    }

    Cell cellOf(const Eigen::Vector3d& placeM) const
    {
        Cell cell;
        for (int axis = 0; axis < 3; ++axis) cell[size_t(axis)] = static_cast<int64_t>(std::floor(placeM[axis] / mCellM));
        return cell;
    }

    /// f(q) for each member q in the 27 cells around `cell` (and, rarely, in cells that wrap
    /// round onto them: a caller tests the distance).
    template <class F>
    void forEachAround(const Cell& cell, const F& f) const
    {
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy) {
                // A column's three cells are one run of keys, searched once (unless z wraps:
                // then a cell at a time).
                std::array<uint64_t, 3> column{};
                for (int dz = -1; dz <= 1; ++dz) column[size_t(dz + 1)] = keyOf({cell[0] + dx, cell[1] + dy, cell[2] + dz});
                const bool oneRun = column[0] < column[2];
                for (size_t run = 0; run < (oneRun ? 1u : 3u); ++run) {
                    const uint64_t lo = column[run], hi = oneRun ? column[2] : column[run];
                    for (auto it = std::lower_bound(mByCell.begin(), mByCell.end(), std::make_pair(lo, uint32_t(0))); it != mByCell.end() && it->first <= hi; ++it)
                        f(it->second);
                }
            }
    }

private:
    /// A cell packed into one key (21 bits a coordinate; cells that wrap round only add pairs
    /// that the distance test then drops).
    static uint64_t keyOf(const Cell& c)
    {
        constexpr uint64_t mask = (uint64_t(1) << 21) - 1;
        return (uint64_t(c[0]) & mask) << 42 | (uint64_t(c[1]) & mask) << 21 | (uint64_t(c[2]) & mask);
    }

    double mCellM;
    std::vector<std::pair<uint64_t, uint32_t>> mByCell;
};

}  // namespace spall
