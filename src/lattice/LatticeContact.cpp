// Contact between a lattice's particles that share no bond. A broken bond still carries its two
// particles' compression, but pieces of one lattice that were never neighbours (the two leaves
// of a wall that folds, shards of a shattered pane) would pass through each other: they meet
// here instead, by the same kind of normal spring along the line of centres.
#include <spall/lattice/Lattice.h>

#include "LatticeForEach.h"
#include "ParticleCells.h"

#include <spall/core/Parallel.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>

namespace spall {

namespace {

/// The Verlet list's skin (in particle edges): pairs this far beyond touching are listed, and
/// the list is made again once some particle has moved half of it.
constexpr double kContactSkin = 0.3;
/// The contact's stiffness k_c against the softest normal bond's k_n: a particle wedged among up
/// to twelve others, each moving against it, rings at ω² ≤ 8 k_c / m = 4 k_n / m (Σ n nᵀ over
/// the twelve edge directions is 4 I), no faster than the lattice's own wave along a bond at the
/// zone's edge (LatticeFrequency.cpp), so it stays within the stable step.
constexpr double kContactStiffnessFraction = 0.5;
/// Particles listed together on one thread.
constexpr size_t kListingBlock = 1024;

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
    std::vector<uint32_t> all(n);
    std::iota(all.begin(), all.end(), 0u);
    const ParticleCells cells(state.positionM, all, cellM);
    // Each block of particles lists its pairs apart, in parallel; joined in block order.
    const size_t blockCount = (n + kListingBlock - 1) / kListingBlock;
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> perBlock(blockCount);
    forEachIndex(blockCount, [&](size_t block) {
        std::vector<std::pair<uint32_t, uint32_t>>& found = perBlock[block];
        for (uint32_t p = uint32_t(block * kListingBlock); p < std::min(n, (block + 1) * kListingBlock); ++p)
            cells.forEachAround(cells.cellOf(state.positionM[p]), [&](uint32_t q) {
                if (q <= p || (mModel.held[p] && mModel.held[q]) || (state.positionM[q] - state.positionM[p]).squaredNorm() >= reach2 || shareABond(p, q))
                    return;
                found.emplace_back(p, q);
            });
        std::sort(found.begin(), found.end());
    });
    mContactCandidates.clear();
    for (const auto& found : perBlock) mContactCandidates.insert(mContactCandidates.end(), found.begin(), found.end());
    mListedAtM = state.positionM;
}

void Lattice::updateContactCandidates()
{
    const double limit = 0.5 * kContactSkin * mModel.spacingM, limit2 = limit * limit;
    // Every step looks at every particle: in parallel, each task in blocks that stop once any
    // task has found one (which one does not matter: the list is made again either way).
    std::atomic<bool> moved{mListedAtM.size() != particleCount()};
    if (!moved)
        forEach((particleCount() + kListingBlock - 1) / kListingBlock, [&](size_t block) {
            if (moved.load(std::memory_order_relaxed)) return;
            for (size_t p = block * kListingBlock; p < std::min(particleCount(), (block + 1) * kListingBlock); ++p)
                if ((state.positionM[p] - mListedAtM[p]).squaredNorm() > limit2) {
                    moved.store(true, std::memory_order_relaxed);
                    return;
                }
        }, 1);
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
