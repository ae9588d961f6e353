// Contact between a lattice's particles that share no bond. A broken bond still carries its two
// particles' compression, but pieces of one lattice that were never neighbours (the two leaves
// of a wall that folds, shards of a shattered pane) would pass through each other: they meet
// here instead, by the same kind of normal spring along the line of centres.
#include <spall/lattice/Lattice.h>

#include <spall/core/Parallel.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace spall {

namespace {

/// The Verlet list's skin (in particle edges): pairs this far beyond touching are listed, and
/// the list is made again once some particle has moved half of it.
constexpr double kContactSkin = 0.3;
/// The contact's stiffness against the softest normal bond's: a particle wedged among up to
/// twelve others must stay within the step that six bonds allow (stableTimeStepS).
constexpr double kContactStiffnessFraction = 0.5;
/// Particles listed together on one thread.
constexpr size_t kListingBlock = 1024;

/// A cell of the listing grid, packed into one key (21 bits a coordinate; cells that wrap round
/// only add pairs that the distance test then drops).
uint64_t cellKey(int64_t x, int64_t y, int64_t z)
{
    constexpr uint64_t mask = (uint64_t(1) << 21) - 1;
    return (uint64_t(x) & mask) << 42 | (uint64_t(y) & mask) << 21 | (uint64_t(z) & mask);
}

}  // namespace

bool Lattice::shareABond(uint32_t p, uint32_t q) const
{
    for (int face = 0; face < 6; ++face) {
        const int32_t b = mModel.bondAcross[p][face];
        if (b >= 0 && (mModel.bonds[size_t(b)].low == q || mModel.bonds[size_t(b)].high == q)) return true;
    }
    return false;
}

void Lattice::listContactCandidates()
{
    const double cellM = (1.0 + kContactSkin) * mModel.spacingM, reach2 = cellM * cellM;
    const size_t n = particleCount();
    std::vector<std::array<int64_t, 3>> cell(n);
    std::vector<std::pair<uint64_t, uint32_t>> byCell(n);
    for (size_t p = 0; p < n; ++p) {
        for (int axis = 0; axis < 3; ++axis) cell[p][size_t(axis)] = static_cast<int64_t>(std::floor(state.positionM[p][axis] / cellM));
        byCell[p] = {cellKey(cell[p][0], cell[p][1], cell[p][2]), uint32_t(p)};
    }
    std::sort(byCell.begin(), byCell.end());
    // Each block of particles lists its pairs apart, in parallel; joined in block order.
    const size_t blockCount = (n + kListingBlock - 1) / kListingBlock;
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> perBlock(blockCount);
    forEachIndex(blockCount, [&](size_t block) {
        std::vector<std::pair<uint32_t, uint32_t>>& found = perBlock[block];
        for (uint32_t p = uint32_t(block * kListingBlock); p < std::min(n, (block + 1) * kListingBlock); ++p)
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy) {
                    // A column's three cells are one run of keys, searched once (unless z wraps:
                    // then a cell at a time).
                    std::array<uint64_t, 3> column{};
                    for (int dz = -1; dz <= 1; ++dz) column[size_t(dz + 1)] = cellKey(cell[p][0] + dx, cell[p][1] + dy, cell[p][2] + dz);
                    const bool oneRun = column[0] < column[2];
                    for (size_t run = 0; run < (oneRun ? 1u : 3u); ++run) {
                        const uint64_t lo = column[run], hi = oneRun ? column[2] : column[run];
                        auto it = std::lower_bound(byCell.begin(), byCell.end(), std::make_pair(lo, uint32_t(0)));
                        for (; it != byCell.end() && it->first <= hi; ++it) {
                            const uint32_t q = it->second;
                            if (q <= p || (mModel.held[p] && mModel.held[q]) || (state.positionM[q] - state.positionM[p]).squaredNorm() >= reach2 ||
                                shareABond(p, q))
                                continue;
                            found.emplace_back(p, q);
                        }
                    }
                }
        std::sort(found.begin(), found.end());
    });
    mContactCandidates.clear();
    for (const auto& found : perBlock) mContactCandidates.insert(mContactCandidates.end(), found.begin(), found.end());
    mListedAtM = state.positionM;
}

void Lattice::updateContactCandidates()
{
    const double limit = 0.5 * kContactSkin * mModel.spacingM, limit2 = limit * limit;
    bool moved = mListedAtM.size() != particleCount();
    for (size_t p = 0; p < particleCount() && !moved; ++p) moved = (state.positionM[p] - mListedAtM[p]).squaredNorm() > limit2;
    if (moved) listContactCandidates();
}

void Lattice::addContactForces()
{
    const double stiffnessNPerM =
        kContactStiffnessFraction * *std::min_element(mModel.stiffness.normalNPerM.begin(), mModel.stiffness.normalNPerM.end());
    // In the sorted list's order, so the sums do not depend on when it was last made.
    for (const auto& [p, q] : mContactCandidates) {
        const Eigen::Vector3d apartM = state.positionM[q] - state.positionM[p];
        const double distanceM = apartM.norm();
        if (distanceM >= mModel.spacingM || distanceM <= 0.0) continue;
        const Eigen::Vector3d onQ = (stiffnessNPerM * (mModel.spacingM - distanceM) / distanceM) * apartM;
        state.bondForceN[q] += onQ;
        state.bondForceN[p] -= onQ;
    }
}

}  // namespace spall
