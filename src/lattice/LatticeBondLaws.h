// A bond's strain and the laws of its failure, as the bond pass calls them for every bond every
// step: inline here, so the pass (LatticeBonds.cpp) is one function a bond and not a dozen calls
// across files (they took about a tenth of the step, issue 49). The public members that report a
// bond's damage (LatticeFailure.cpp) call the same functions.
#pragma once

#include <spall/lattice/Lattice.h>

#include "BondLawKernel.h"
#include "BondStrainKernel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace spall {

namespace bond_laws {

/// Damage on a linear softening line from u0 to uf at the driver κ: the secant stiffness
/// (1 − D) κ / u0 = (uf − κ) / (uf − u0) (Bažant & Oh 1983's crack band, linear).
inline double lineDamage(double kappa, double u0, double uf)
{
    if (kappa <= u0) return 0.0;
    if (kappa >= uf) return 1.0;
    return 1.0 - (u0 / kappa) * (uf - kappa) / (uf - u0);
}

/// The softening line's peak stretch u0 and the stretch uf where it carries nothing, for the
/// bond's strength scale s and strength factor f: s f u0 and uf / (s f), so the energy under it,
/// ½ k u0 uf, is the material's Gf h² whatever the scatter and the rate (unit: m).
inline std::pair<double, double> softeningLineM(const BondHistory& history, const LatticeStiffness::Strength& strength)
{
    const double scale = history.strengthScale * history.strengthFactor;
    return {scale * strength.peakStretchM, strength.zeroTractionStretchM / scale};
}

/// Whether a bond of this strength breaks at its peak: its voxels are too large to soften
/// (Strength::peakStretchM), whatever its own strength scale.
inline bool snapsAtPeak(const LatticeStiffness::Strength& strength)
{
    return strength.zeroTractionStretchM <= strength.peakStretchM;
}

/// 0 intact … 1 broken on the softening line, from the largest equivalent stretch.
inline double softeningDamage(const BondHistory& history, const LatticeStiffness::Strength& strength)
{
    const auto [u0, uf] = softeningLineM(history, strength);
    const double kappa = history.maxEquivalentStretchM;
    if (kappa > u0 && snapsAtPeak(strength)) return 1.0;
    return lineDamage(kappa, u0, uf);
}

/// D_c: 0 … 1 on the compressive softening line.
inline double crushingDamage(const BondHistory& history, const LatticeStiffness::Strength& strength)
{
    if (history.maxCrushingShorteningM <= 0.0) return 0.0;
    // The strength scale (scatter, a weak joint) scales crushing as it scales cracking.
    return lineDamage(history.maxCrushingShorteningM, history.strengthScale * strength.crushingPeakShorteningM,
                      strength.crushingEndShorteningM / history.strengthScale);
}

/// D_t: cracking's damage, on the softening line or by Davison–Stevens.
inline double crackingDamage(const BondHistory& history, const LatticeStiffness::Strength& strength, LatticeDamageLaw law)
{
    return law == LatticeDamageLaw::DavisonStevens ? history.rateDamage : softeningDamage(history, strength);
}

/// Cracking and crushing together, 1 − (1 − D_t)(1 − D_c).
inline double bondDamage(const BondHistory& history, const LatticeStiffness::Strength& strength, LatticeDamageLaw law)
{
    const double cracked = crackingDamage(history, strength, law), crushed = crushingDamage(history, strength);
    // Without crushing, exactly D_t (1 − (1 − D_t) need not round back to it).
    return crushed == 0.0 ? cracked : 1.0 - (1.0 - cracked) * (1.0 - crushed);
}

/// The shear traction over the shear strength: |(k_b d_b, k_c d_c)| / (h² c) across axis a.
template <typename Vector>
inline double shearIndexOf(const Eigen::Vector3d& perM, const Vector& displacementM, int a)
{
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    // Equal factors (isotropic): one product, as the golden states were recorded with.
    if (perM[b] == perM[c]) {
        const double components[3] = {displacementM[0], displacementM[1], displacementM[2]};
        return bond_law::isotropicShearIndex(perM[b], components, components[a]);
    }
    return std::hypot(perM[b] * displacementM[b], perM[c] * displacementM[c]);
}

/// Rotation vector of a unit quaternion (angle × axis), the short way round: by its series
/// where the angle is small (BondStrainKernel.h), else 2 atan2(s, w) / s.
inline Eigen::Vector3d rotationVector(Eigen::Quaterniond q)
{
    const double coefficients[4] = {q.x(), q.y(), q.z(), q.w()};
    double series[3];
    bool small = false;
    bond_strain::smallRotationVector(coefficients, series, small);
    if (small) return {series[0], series[1], series[2]};
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    const double s = std::sqrt(q.vec().squaredNorm());
    return (2.0 * std::atan2(s, q.w()) / s) * q.vec();
}

/// The rotation matrix of a quaternion of any length (its own normalised; BondStrainKernel.h).
inline Eigen::Matrix3d rotationMatrixOf(const Eigen::Quaterniond& q)
{
    const double coefficients[4] = {q.x(), q.y(), q.z(), q.w()};
    double r[3][3];
    bond_strain::rotationMatrixOf(coefficients, r);
    Eigen::Matrix3d m;
    m << r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2];
    return m;
}

/// The rotation from qa to qb in a bond's frame, where the series does not hold (the arctangent).
inline Eigen::Vector3d largeTurnRad(const Eigen::Matrix3d& frame, const Eigen::Quaterniond& qa, const Eigen::Quaterniond& qb)
{
    return frame.transpose() * rotationVector(qb * qa.conjugate());
}

}  // namespace bond_laws

inline BondStrain Lattice::strainOf(const LatticeBond& bond) const
{
    const Eigen::Quaterniond& qa = state.orientation[bond.low];
    const Eigen::Quaterniond& qb = state.orientation[bond.high];
    BondStrain s;
    if (bond.pinned) {
        // A pin measures its voxel's centre in the held point's frame, across its axis only: the
        // voxel may turn on it and slide toward or away from the support (glazing's clearance).
        s.frame = bond_laws::rotationMatrixOf(mModel.held[bond.low] ? qa : qb);
        s.displacementM = s.frame.transpose() * (state.positionM[bond.high] - state.positionM[bond.low]);
        s.displacementM[bond.axis] = 0.0;
        return s;
    }
    const auto endState = [&](uint32_t p) {
        bond_strain::EndState<double> e;
        for (int k = 0; k < 3; ++k) e.position[k] = state.positionM[p][k], e.velocity[k] = state.velocityMS[p][k];
        for (int k = 0; k < 4; ++k) e.quaternion[k] = state.orientation[p].coeffs()[k];
        return e;
    };
    bond_strain::Strain<double> measured;
    bool smallTurn = false;
    bond_strain::halfwayStrain(endState(bond.low), endState(bond.high), bond.axis, mModel.spacingM, measured, smallTurn);
    s.frame << measured.frame[0][0], measured.frame[0][1], measured.frame[0][2], measured.frame[1][0], measured.frame[1][1],
        measured.frame[1][2], measured.frame[2][0], measured.frame[2][1], measured.frame[2][2];
    s.displacementM = Eigen::Vector3d(measured.displacementM[0], measured.displacementM[1], measured.displacementM[2]);
    s.rotationRad = smallTurn ? Eigen::Vector3d(measured.rotationRad[0], measured.rotationRad[1], measured.rotationRad[2])
                              : bond_laws::largeTurnRad(s.frame, qa, qb);
    return s;
}

inline double Lattice::confinementPa(uint32_t p, int a) const
{
    double leastCompressionPa = std::numeric_limits<double>::infinity();
    for (const int lateral : {(a + 1) % 3, (a + 2) % 3}) {
        double sumPa = 0.0;
        for (const int face : {2 * lateral, 2 * lateral + 1})
            if (const int32_t b = mModel.bondAcross[p][face]; b >= 0) sumPa += mBondNormalStressPa[size_t(b)];
        leastCompressionPa = std::min(leastCompressionPa, -sumPa * mModel.inverseBondCount[p][lateral]);
    }
    return std::max(0.0, leastCompressionPa);
}

inline double Lattice::crushingShorteningM(size_t b, double normalM) const
{
    const LatticeBond& bond = mModel.bonds[b];
    const LatticeStiffness::Strength& strength = mModel.stiffness.strength[bond.strengthClass];
    if (strength.compressiveStrengthPa <= 0.0 || bond.pinned || normalM >= 0.0) return 0.0;
    const int a = bond.axis;
    const double compressionPa =
        -(mModel.stiffness.normalModulusPa[size_t(a)] * normalM / mModel.spacingM + 0.5 * (mUncrushedLambdaTracePa[bond.low] + mUncrushedLambdaTracePa[bond.high]));
    if (compressionPa <= 0.0) return 0.0;
    // Confinement only strengthens (σ1 ≥ fc for σ3 ≥ 0): a compression that could not pass the
    // largest shortening so far even unconfined grows nothing, and needs no confinement read.
    const double unconfinedM = compressionPa / strength.compressiveStrengthPa * strength.crushingPeakShorteningM;
    if (unconfinedM <= state.bondHistory[b].maxCrushingShorteningM) return unconfinedM;
    const double fc = strength.compressiveStrengthPa, lateralPa = 0.5 * (confinementPa(bond.low, a) + confinementPa(bond.high, a));
    const double strengthPa = lateralPa + fc * std::sqrt(strength.confinementM * lateralPa / fc + 1.0);
    return compressionPa / strengthPa * strength.crushingPeakShorteningM;
}

template <typename Strain>
inline double Lattice::equivalentStretchM(size_t b, const Strain& strain, double lengthM, double damage) const
{
    const LatticeBond& bond = mModel.bonds[b];
    const int a = bond.axis;
    const LatticeModel::FailureTerms& terms = mModel.failureTerms[bond.strengthClass][size_t(a)];
    // The shear displacement: across the bond's axis in its half-way frame.
    const double normalM = strain.displacementM[a];
    const double shearIndex = bond_laws::shearIndexOf(terms.shearIndexPerM, strain.displacementM, a);
    // The stretch at the face's most stretched corner: the moment the bond carries, (1 − D) of
    // its bending stiffness times θ, opens one edge by (1 − D) θ h/2 per axis across it, so the
    // outermost bonds of a bent member see the strain of its surface, E κ t/2, as a continuum
    // would (the parallel bond's σ = F/A + |M| R/I, Potyondy & Cundall 2004), not that of their
    // centres, t/2 − h/2 from the neutral axis. As the bond softens its moment goes, and its
    // opening alone carries it to the end of the softening line, so it still dissipates Gf.
    const auto& rotation = strain.rotationRad;
    const double stretchM = bond.pinned ? 0.0  // a pin fails in shear
                                        : lengthM - mModel.spacingM + bond_law::bendingStretchM(mModel.spacingM, 1.0 - damage, double(rotation[(a + 1) % 3]),
                                                                                                double(rotation[(a + 2) % 3]));
    const bond_law::FailureTerms<double> failure{terms.tensionIndexPerM, terms.normalIndexPerM, terms.indexPerPa, terms.frictionCoefficient};
    if (stretchM >= 0.0) return bond_law::failureIndexInTension(stretchM, shearIndex, failure) * terms.peakStretchM;
    // The compression across the bond: its spring's and its particles' volumetric share, as the
    // last force pass left them (a substep behind; a function of the saved state).
    const double sharesPa = mVolumetricStressShare[bond.low][a] + mVolumetricStressShare[bond.high][a];
    return bond_law::failureIndexInCompression(normalM, shearIndex, sharesPa, failure) * terms.peakStretchM;
}

inline bool Lattice::growBondDamage(size_t b, double equivalentStretchNowM, double crushingShorteningNowM, double strainRatePerS, double dtS)
{
    BondHistory& history = state.bondHistory[b];
    const bool crushing = crushingShorteningNowM > history.maxCrushingShorteningM;
    if (crushing) history.maxCrushingShorteningM = crushingShorteningNowM;
    const double increaseM = equivalentStretchNowM - history.maxEquivalentStretchM;
    if (increaseM > 0.0) {
        const bool undamaged = history.maxEquivalentStretchM <= bond_laws::softeningLineM(history, strengthOf(b)).first;
        history.maxEquivalentStretchM += increaseM;
        if (undamaged) followStrengthRate(history, increaseM, strainRatePerS);
    }
    if (mModel.damageLaw == LatticeDamageLaw::DavisonStevens) {
        history.rateDamage = rateDamageAfter(b, equivalentStretchNowM, dtS);
        return true;
    }
    return increaseM > 0.0 || crushing;
}

inline Eigen::Vector3d Lattice::completeBondForce(size_t b, const Eigen::Vector3d& armM) const
{
    // The volumetric energy's force along the bond: d(Σ ½ λ h³ (tr ε)²) / d(length).
    const LatticeBond& bond = mModel.bonds[b];
    const BondForceTerms& terms = mBondTerms[b];
    const double sharesPa = mVolumetricStressShare[bond.low][bond.axis] + mVolumetricStressShare[bond.high][bond.axis];
    return terms.forceOnHighN - (terms.volumetricAreaPerArmM * sharesPa) * armM;
}

}  // namespace spall
