#include <spall/lattice/LatticePairContact.h>

#include "ParticleCells.h"

#include <spall/core/Error.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace spall {

namespace {

/// The Verlet list's skin, in the touching distance: as within a lattice (LatticeContact.cpp).
constexpr double kPairSkin = 0.3;

/// The voxels' particles of `lattice` inside `box` (not its support points: they stand for the
/// ground and the boxes that hold it, which other bodies meet as such).
std::vector<uint32_t> particlesIn(const Lattice& lattice, const Eigen::AlignedBox3d& box)
{
    std::vector<uint32_t> inside;
    for (uint32_t p = 0; p < lattice.model().voxelParticleCount; ++p)
        if (box.contains(lattice.state.positionM[p])) inside.push_back(p);
    return inside;
}

Eigen::AlignedBox3d grown(Eigen::AlignedBox3d box, double marginM)
{
    box.min().array() -= marginM;
    box.max().array() += marginM;
    return box;
}

}  // namespace

double fastestParticleSpeedMS(const Lattice& lattice)
{
    double fastest2 = 0.0;
    for (const Eigen::Vector3d& v : lattice.state.velocityMS) fastest2 = std::max(fastest2, v.squaredNorm());
    return std::sqrt(fastest2);
}

double stepTravelBoundM(const Lattice& lattice, double dtS)
{
    // A drift of d from x lands within |d| (1 + 2^-52) plus half an ulp of x of where it should:
    // a relative and a nanometre's margin cover both for places within 10^6 m.
    return dtS * fastestParticleSpeedMS(lattice) * (1.0 + 1e-9) + 1e-9;
}

Eigen::AlignedBox3d particleBox(const Lattice& lattice)
{
    Eigen::AlignedBox3d box;
    for (size_t p = 0; p < lattice.model().voxelParticleCount; ++p) box.extend(lattice.state.positionM[p]);
    return box;
}

LatticePairContact::LatticePairContact(const Lattice& a, const Lattice& b, std::optional<double> overlapExcuseM)
    : mTouchM(0.5 * (a.model().spacingM + b.model().spacingM)), mSkinM(kPairSkin * mTouchM)
{
    // Each side's half edge is twice as stiff as its whole bond; never stiffer than the softer
    // side's bond, the ground's contact spring, which the lattices' stable step allows.
    const double ka = 2.0 * a.surfaceStiffnessNPerM(), kb = 2.0 * b.surfaceStiffnessNPerM();
    mStiffnessNPerM = std::min(ka * kb / (ka + kb), 0.5 * std::min(ka, kb));
    if (overlapExcuseM) {
        mOverlapExcuseM = *overlapExcuseM;
        return;
    }
    listCandidates(a, b);
    mOverlapExcuseM = deepestOverlapM(a, b);
}

double LatticePairContact::deepestOverlapM(const Lattice& a, const Lattice& b) const
{
    double deepestM = 0.0;
    for (const auto& [p, q] : mCandidates) deepestM = std::max(deepestM, mTouchM - (b.state.positionM[q] - a.state.positionM[p]).norm());
    return deepestM;
}

namespace {

/// The largest squared distance of a place from where it was listed (unit: m²).
double farthestMoveSquaredM2(const std::vector<Eigen::Vector3d>& placesM, const std::vector<Eigen::Vector3d>& listedM)
{
    double farthest2 = 0.0;
    for (size_t p = 0; p < placesM.size(); ++p) farthest2 = std::max(farthest2, (placesM[p] - listedM[p]).squaredNorm());
    return farthest2;
}

}  // namespace

bool LatticePairContact::movedHalfTheSkin(const Lattice& a, const Lattice& b, double travelAM, double travelBM)
{
    if (mListedAM.size() != a.particleCount() || mListedBM.size() != b.particleCount()) return true;
    // Below half the skin by a margin the bounds' rounding cannot cross: no particle got there.
    mMovedBoundAM += travelAM;
    mMovedBoundBM += travelBM;
    const double halfSkinM = 0.5 * mSkinM;
    if (std::max(mMovedBoundAM, mMovedBoundBM) <= halfSkinM * (1.0 - 1e-9)) return false;
    const double movedA2 = farthestMoveSquaredM2(a.state.positionM, mListedAM), movedB2 = farthestMoveSquaredM2(b.state.positionM, mListedBM);
    mMovedBoundAM = std::sqrt(movedA2);
    mMovedBoundBM = std::sqrt(movedB2);
    return std::max(movedA2, movedB2) > halfSkinM * halfSkinM;
}

void LatticePairContact::listCandidates(const Lattice& a, const Lattice& b)
{
    const double reachM = mTouchM + mSkinM, reach2 = reachM * reachM;
    // Only particles within reach of the other lattice's box can have a partner.
    const std::vector<uint32_t> nearB = particlesIn(a, grown(particleBox(b), reachM));
    const ParticleCells cellsOfA(a.state.positionM, nearB, reachM);
    mCandidates.clear();
    for (const uint32_t q : particlesIn(b, grown(particleBox(a), reachM)))
        cellsOfA.forEachAround(cellsOfA.cellOf(b.state.positionM[q]), [&](uint32_t p) {
            if ((b.state.positionM[q] - a.state.positionM[p]).squaredNorm() < reach2) mCandidates.emplace_back(p, q);
        });
    std::sort(mCandidates.begin(), mCandidates.end());
    mListedAM = a.state.positionM;
    mListedBM = b.state.positionM;
    mMovedBoundAM = mMovedBoundBM = 0.0;
}

void LatticePairContact::addForces(Lattice& a, Lattice& b, double travelAM, double travelBM)
{
    if (movedHalfTheSkin(a, b, travelAM, travelBM)) listCandidates(a, b);
    // In the sorted list's order, so the sums do not depend on when it was last made.
    const double pushFromM = mTouchM - mOverlapExcuseM;
    double deepestM = 0.0;
    for (const auto& [p, q] : mCandidates) {
        const Eigen::Vector3d apartM = b.state.positionM[q] - a.state.positionM[p];
        const double distanceM = apartM.norm();
        deepestM = std::max(deepestM, mTouchM - distanceM);
        if (distanceM >= pushFromM || distanceM <= 0.0) continue;
        const Eigen::Vector3d onB = (mStiffnessNPerM * (pushFromM - distanceM) / distanceM) * apartM;
        b.state.bondForceN[q] += onB;
        a.state.bondForceN[p] -= onB;
        mPushed = true;
    }
    mOverlapExcuseM = std::min(mOverlapExcuseM, deepestM);
}

namespace {

/// A coasting lattice (DeformableBody::coasting) steps as a lattice from the step its
/// particles first meet the ground, a collider or another lattice's.
void stopCoastingOnceTouched(const std::vector<DeformableBody*>& group, const std::vector<std::pair<size_t, size_t>>& touching,
                             const std::vector<LatticePairContact*>& contacts)
{
    for (DeformableBody* d : group)
        if (d->lattice.pressedOnASurface()) d->coasting = false;
    for (size_t c = 0; c < touching.size(); ++c)
        if (contacts[c]->pushed()) group[touching[c].first]->coasting = group[touching[c].second]->coasting = false;
}

}  // namespace

int64_t advanceTogether(const std::vector<DeformableBody*>& group, const std::vector<std::pair<size_t, size_t>>& touching,
                        const std::vector<LatticePairContact*>& contacts, double dtS, const std::function<bool()>& abandon)
{
    SPALL_CHECK(contacts.size() == touching.size());
    int64_t particleSteps = 0;
    double stableS = std::numeric_limits<double>::infinity();
    for (DeformableBody* d : group) {
        // Catching up steps under the gathered forces: this step's wait aside.
        std::vector<Eigen::Vector3d> thisStepN = d->lattice.externalForceN;
        particleSteps += catchUpDeformable(*d);
        d->lattice.externalForceN = std::move(thisStepN);
        stableS = std::min(stableS, d->lattice.stableTimeStepS());
    }
    const int64_t steps = static_cast<int64_t>(std::ceil(dtS / stableS * (1.0 - 1e-12)));
    const double stepS = dtS / double(steps);
    std::vector<double> travelM(group.size());
    for (int64_t s = 0; s < steps; ++s) {
        if (abandon && abandon())
            throw StepAbandoned("a step of the deformable phase was given up after " + std::to_string(s) + " of its " + std::to_string(steps) +
                                " steps of lattices in contact");
        for (DeformableBody* d : group) d->coasting ? d->lattice.coast(stepS) : d->lattice.moveAndMeasure(stepS);
        // Each lattice's travel once, for all its pairs; the first step's is not known (the
        // lattices may have moved since their pairs last met: catching up, stepped alone), nor a
        // coasting lattice's (it turned along an arc, not along its velocities).
        for (size_t g = 0; g < group.size(); ++g)
            travelM[g] = s == 0 || group[g]->coasting ? std::numeric_limits<double>::infinity() : stepTravelBoundM(group[g]->lattice, stepS);
        for (size_t c = 0; c < touching.size(); ++c)
            contacts[c]->addForces(group[touching[c].first]->lattice, group[touching[c].second]->lattice, travelM[touching[c].first],
                                   travelM[touching[c].second]);
        for (DeformableBody* d : group) d->lattice.finishStep(stepS);
        stopCoastingOnceTouched(group, touching, contacts);
    }
    for (const DeformableBody* d : group) particleSteps += steps * static_cast<int64_t>(d->lattice.particleCount());
    return particleSteps;
}

}  // namespace spall
