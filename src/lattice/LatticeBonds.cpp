// The bonds' pass of a lattice step: each bond's strain in its half-way frame, its damage and its
// spring, dashpot and bending terms (measureBond, each bond writing only its own entry); each
// particle's volumetric strain; and each particle gathering its six bonds' forces in face order,
// each completed with the volumetric force, so the sums do not depend on the thread count.
#include "LatticeBondLaws.h"
#include "LatticeForEach.h"

#include <cmath>

namespace spall {

void Lattice::computeVolumetricStrain()
{
    mVolumetricStrain.resize(particleCount());
    mVolumetricStressShare.resize(particleCount());
    const bool crushes = !mUncrushedLambdaTracePa.empty();
    const double inverseH = 1.0 / mModel.spacingM;
    forEach(
        particleCount(),
        [&](size_t p) {
            double trace = 0.0, uncrushedTrace = 0.0;
            for (int axis = 0; axis < 3; ++axis) {
                double sum = 0.0, uncrushedSum = 0.0;
                for (const int face : {2 * axis, 2 * axis + 1}) {
                    const int32_t b = mModel.bondAcross[p][face];
                    if (b < 0) continue;
                    sum += mBondTerms[size_t(b)].effectiveStretchM * inverseH;
                    if (crushes) uncrushedSum += mBondTerms[size_t(b)].uncrushedStretchM * inverseH;
                }
                trace += sum * mModel.inverseBondCount[p][axis];
                uncrushedTrace += uncrushedSum * mModel.inverseBondCount[p][axis];
            }
            mVolumetricStrain[p] = trace;
            // d(½ λ h³ (tr ε)²) / d(stretch of one bond along the axis) / h³.
            mVolumetricStressShare[p] = mModel.lambdaPa[p] * trace * mModel.inverseBondCount[p];
            if (crushes) mUncrushedLambdaTracePa[p] = mModel.lambdaPa[p] * uncrushedTrace;
        });
}

uint8_t Lattice::measureBond(size_t b, double dtS, bool growDamage)
{
    const LatticeBond& bond = mModel.bonds[b];
    const LatticeStiffness& k = mModel.stiffness;
    const BondStrain s = strainOf(bond);
    const int a = bond.axis;
    BondForceTerms& terms = mBondTerms[b];
    const Eigen::Vector3d armM = armOf(b);
    const double lengthM = armM.norm();
    const Eigen::Vector3d along = armM * (1.0 / lengthM);
    const double openingRateMS = (state.velocityMS[bond.high] - state.velocityMS[bond.low]).dot(along);
    const BondHistory& history = state.bondHistory[b];
    const LatticeStiffness::Strength& strength = k.strength[bond.strengthClass];
    const double damageBefore = bond_laws::bondDamage(history, strength, mModel.damageLaw);
    double damage = damageBefore;
    if (growDamage && growBondDamage(b, equivalentStretchM(b, s, lengthM, damage), crushingShorteningM(b, s.displacementM[a]),
                                     std::abs(openingRateMS) / mModel.spacingM, dtS))
        damage = bond_laws::bondDamage(history, strength, mModel.damageLaw);
    // Compression carries what crushing left (a crack in tension or shear closes on itself).
    const double crushed = bond_laws::crushingDamage(history, strength), uncrushed = 1.0 - crushed;
    const bool broke = damage >= 1.0 && damageBefore < 1.0;
    // What a pin held is lost where it fails (the glazing's own dissipation).
    const bool snapped = broke && mModel.damageLaw == LatticeDamageLaw::Softening && bond_laws::snapsAtPeak(strength) && !bond.pinned &&
                         bond_laws::crackingDamage(history, strength, mModel.damageLaw) >= 1.0;
    if (snapped) mSnapped[b] = 1;
    const double intact = 1.0 - damage, sqrtIntact = std::sqrt(intact);
    const bool opening = lengthM > mModel.spacingM;
    Eigen::Vector3d local = (-intact * k.shearNPerM[a]).cwiseProduct(s.displacementM);
    local[a] = -intact * k.normalNPerM[a] * s.displacementM[a];
    terms.forceOnHighN = s.frame * local;
    if (bond.pinned) {
        // Across its axis only: no contact, dashpot, moment or volumetric share.
        terms.bendingMomentNm.setZero();
        terms.effectiveStretchM = terms.uncrushedStretchM = terms.volumetricAreaPerArmM = 0.0;
        return uint8_t(broke ? kBroke : 0);
    }
    // What cracking took still carries compression, as contact: along the line of centres, and
    // only while the two cubes overlap. (In the bond's frame it would push apart particles that
    // have slid past each other or turned over, which feeds energy into a shattered lattice.)
    const double overlapM = mModel.spacingM - lengthM;
    if (intact < uncrushed && overlapM > 0.0) terms.forceOnHighN += (uncrushed - intact) * k.normalNPerM[a] * overlapM * along;
    // The crushed part's rubble carries again once squeezed past the softening line's end:
    // k (D_c overlap − uf), which grows with D_c from nothing, so no force jumps in.
    const double rubbleM = crushed * overlapM - strength.crushingEndShorteningM;
    if (crushed > 0.0 && rubbleM > 0.0) terms.forceOnHighN += k.normalNPerM[a] * rubbleM * along;
    // A crack opening carries no viscous stress either: the dashpot softens with the spring.
    if (mModel.bulkViscosity > 0.0) terms.forceOnHighN -= (opening ? intact : uncrushed) * mModel.bulkViscosity * mModel.dashpotPerViscosityNSPerM * openingRateMS * along;
    Eigen::Vector3d bending = -intact * k.bendingNmPerRad[a] * s.rotationRad;
    bending[a] = -intact * k.twistingNmPerRad[a] * s.rotationRad[a];
    terms.bendingMomentNm = s.frame * bending;
    const double sqrtUncrushed = crushed == 0.0 ? 1.0 : std::sqrt(uncrushed);
    terms.uncrushedStretchM = opening ? sqrtIntact * (lengthM - mModel.spacingM) : lengthM - mModel.spacingM;
    terms.effectiveStretchM = opening ? terms.uncrushedStretchM : sqrtUncrushed * terms.uncrushedStretchM;
    terms.volumetricAreaPerArmM = (opening ? sqrtIntact : sqrtUncrushed) * mModel.spacingM * mModel.spacingM / lengthM;
    return uint8_t((snapped ? kSnapped : 0) | (broke ? kBroke : 0));
}

void Lattice::gatherBondForces(size_t p)
{
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
    for (int face = 0; face < 6; ++face) {
        const int32_t b = mModel.bondAcross[p][face];
        if (b < 0) continue;
        const LatticeBond& bond = mModel.bonds[size_t(b)];
        const Eigen::Vector3d armM = armOf(size_t(b));
        const Eigen::Vector3d forceOnHighN = completeBondForce(size_t(b), armM);
        const Eigen::Vector3d pairMomentNm = bond.pinned ? Eigen::Vector3d::Zero() : Eigen::Vector3d(-0.5 * armM.cross(forceOnHighN));
        const Eigen::Vector3d& bendingMomentNm = mBondTerms[size_t(b)].bendingMomentNm;
        if (face & 1) {  // the bond across p's +axis face: p is its low end
            force -= forceOnHighN;
            moment += pairMomentNm - bendingMomentNm;
            // Read across its particles by the next substep's crushing (confinementPa).
            if (!mBondNormalStressPa.empty())
                mBondNormalStressPa[size_t(b)] = -forceOnHighN.dot(armM) / (armM.norm() * mModel.spacingM * mModel.spacingM);
        } else {
            force += forceOnHighN;
            moment += pairMomentNm + bendingMomentNm;
        }
    }
    state.bondForceN[p] = force;
    state.bondMomentNm[p] = moment;
}

}  // namespace spall
