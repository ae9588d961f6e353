// A lattice's energies and momenta, and the energy a snapping bond gives back to its particles
// (the last pass of a step, Lattice::step).
#include "LatticeBondLaws.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace spall {

namespace {

/// A bond's shear springs' energy, doubled: Σ k_b d_b² over the directions b across its axis.
double shearEnergyTerm(const Eigen::Vector3d& factor, const Eigen::Vector3d& displacement, int axis)
{
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    // Equal factors (every plane of an isotropic material): one product, as the golden states
    // were recorded with.
    if (factor[b] == factor[c]) return factor[b] * (displacement.squaredNorm() - displacement[axis] * displacement[axis]);
    return factor[b] * displacement[b] * displacement[b] + factor[c] * displacement[c] * displacement[c];
}

}  // namespace

double Lattice::elasticEnergyJ(size_t b, const BondStrain& s, double intact) const
{
    const LatticeStiffness& k = mModel.stiffness;
    const int a = mModel.bonds[b].axis;
    const double normal = s.displacementM[a], twist = s.rotationRad[a];
    return 0.5 * intact *
           (k.normalNPerM[a] * normal * normal + shearEnergyTerm(k.shearNPerM[a], s.displacementM, a) +
            k.bendingNmPerRad[a] * (s.rotationRad.squaredNorm() - twist * twist) + k.twistingNmPerRad[a] * twist * twist);
}

void Lattice::releaseSnapEnergies()
{
    std::vector<uint32_t> snapped;
    for (size_t b = 0; b < bondCount(); ++b)
        if (mSnapped[b]) {
            snapped.push_back(uint32_t(b));
            mSnapped[b] = 0;
        }
    // What the open ones' stretches held in each particle's tr ε, taken out together: the
    // particle's volumetric energy with them counted (tr ε now plus their shares) less without.
    std::unordered_map<uint32_t, double> removedTrace;
    const auto traceShare = [&](uint32_t b, uint32_t p) {
        const double stretchM = armOf(b).norm() - mModel.spacingM;
        return stretchM > 0.0 ? stretchM / mModel.spacingM * mModel.inverseBondCount[p][mModel.bonds[b].axis] : 0.0;
    };
    for (const uint32_t b : snapped)
        for (const uint32_t p : {mModel.bonds[b].low, mModel.bonds[b].high}) removedTrace[p] += traceShare(b, p);
    const double h3 = mModel.spacingM * mModel.spacingM * mModel.spacingM;
    for (const uint32_t b : snapped) {
        double volumetricJ = 0.0;
        for (const uint32_t p : {mModel.bonds[b].low, mModel.bonds[b].high}) {
            const double removed = removedTrace[p], trace = mVolumetricStrain[p];
            if (removed <= 0.0) continue;
            const double particleJ = 0.5 * mModel.lambdaPa[p] * h3 * ((trace + removed) * (trace + removed) - trace * trace);
            volumetricJ += particleJ * traceShare(b, p) / removed;
        }
        releaseSnapEnergy(b, volumetricJ);
    }
}

void Lattice::releaseSnapEnergy(size_t b, double volumetricJ)
{
    const LatticeBond& bond = mModel.bonds[b];
    const int a = bond.axis;
    const int freeEnds = int(!mModel.held[bond.low]) + int(!mModel.held[bond.high]);
    if (freeEnds == 0) return;
    const BondStrain strain = strainOf(bond);
    const Eigen::Vector3d armM = armOf(b);
    const double lengthM = armM.norm();
    double lostJ = elasticEnergyJ(b, strain, 1.0) + volumetricJ;
    // Closed, it still carries its compression as contact: its normal spring's energy stays.
    if (lengthM < mModel.spacingM) lostJ -= 0.5 * mModel.stiffness.normalNPerM[size_t(a)] * strain.displacementM[a] * strain.displacementM[a];
    // A step carries a bond past its strength by up to a third of its peak stretch, and the
    // energy of that overshoot was never paid for by the particles (their next kick would have
    // paid it): what it held on its failure surface is the energy, quadratic in a strain the
    // failure index is linear in, over the index squared (its peak raised by the rate law).
    const LatticeStiffness::Strength& strength = mModel.stiffness.strength[bond.strengthClass];
    const double index = equivalentStretchM(b, strain, lengthM, 0.0) / softeningLineM(b).first;
    const double releasedJ = lostJ / std::max(1.0, index * index) - strength.fractureEnergyJPerM2 * mModel.spacingM * mModel.spacingM;
    if (!(releasedJ > 0.0)) return;
    // Kinetic energy added by dv apart, shared between the free ends (a held end takes none):
    // E = m (dv w + dv² / 2) for one free end and m (dv w / 2 + dv² / 4) for two (each moving
    // dv / 2), w the free ends' opening rate: dv = -w + sqrt(w² + 2 n E / m), n free ends.
    const Eigen::Vector3d along = armM / lengthM;
    const auto freeVelocity = [&](uint32_t p) { return mModel.held[p] ? Eigen::Vector3d::Zero() : state.velocityMS[p]; };
    const double w = (freeVelocity(bond.high) - freeVelocity(bond.low)).dot(along);
    const double dv = -w + std::sqrt(w * w + 2.0 * freeEnds * releasedJ / mModel.particleMassKg);
    if (!mModel.held[bond.high]) state.velocityMS[bond.high] += (dv / freeEnds) * along;
    if (!mModel.held[bond.low]) state.velocityMS[bond.low] -= (dv / freeEnds) * along;
}

double Lattice::kineticEnergyJ() const
{
    double sum = 0.0;
    for (size_t p = 0; p < particleCount(); ++p)
        sum += 0.5 * mModel.particleMassKg * state.velocityMS[p].squaredNorm() + 0.5 * mModel.particleInertiaKgM2 * state.angularVelocityRadS[p].squaredNorm();
    return sum;
}

double Lattice::bondStrainEnergyJ(size_t b) const
{
    const LatticeBond& bond = mModel.bonds[b];
    const double intact = 1.0 - bondDamage(b), crushed = crushingDamage(b);
    const double overlapM = bond.pinned ? 0.0 : std::max(0.0, mModel.spacingM - (state.positionM[bond.high] - state.positionM[bond.low]).norm());
    // measureBond's contact terms: the closed crack's and the crushed part's rubble, whose force
    // k (D_c x − uf) has the potential k (D_c x − uf)² / 2 D_c at its D_c.
    const double rubbleM = crushed > 0.0 ? std::max(0.0, crushed * overlapM - mModel.stiffness.strength[bond.strengthClass].crushingEndShorteningM) : 0.0;
    const double normalNPerM = mModel.stiffness.normalNPerM[size_t(bond.axis)];
    return elasticEnergyJ(b, strainOf(bond), intact) + 0.5 * (1.0 - crushed - intact) * normalNPerM * overlapM * overlapM +
           (crushed > 0.0 ? 0.5 * normalNPerM * rubbleM * rubbleM / crushed : 0.0);
}

double Lattice::volumetricEnergyJ(size_t p) const
{
    return 0.5 * mModel.lambdaPa[p] * mModel.spacingM * mModel.spacingM * mModel.spacingM * mVolumetricStrain[p] * mVolumetricStrain[p];
}

double Lattice::strainEnergyJ() const
{
    double sum = 0.0;
    for (size_t b = 0; b < mModel.bonds.size(); ++b) sum += bondStrainEnergyJ(b);
    for (size_t p = 0; p < particleCount(); ++p) sum += volumetricEnergyJ(p);
    return sum;
}

Eigen::Vector3d Lattice::linearMomentum() const
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& v : state.velocityMS) sum += mModel.particleMassKg * v;
    return sum;
}

Eigen::Vector3d Lattice::angularMomentumAboutOrigin() const
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (size_t p = 0; p < particleCount(); ++p)
        sum += state.positionM[p].cross(mModel.particleMassKg * state.velocityMS[p]) + mModel.particleInertiaKgM2 * state.angularVelocityRadS[p];
    return sum;
}

}  // namespace spall
