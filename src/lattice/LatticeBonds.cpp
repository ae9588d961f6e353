// The bonds' pass of a lattice step: each bond's strain in its half-way frame, its damage and its
// spring, dashpot and bending terms (measureBond, each bond writing only its own entry); each
// particle's volumetric strain; the volumetric force completing each bond's; and each particle
// gathering its six bonds' forces in face order, so the sums do not depend on the thread count.
#include "LatticeForEach.h"

#include <cmath>

namespace spall {

namespace {

/// Rotation vector of a unit quaternion (angle × axis), the short way round. Bonds turn by
/// small angles: there 2 atan(s/w)/s by its series (relative error below 1e-13 for s/w < 1e-3).
Eigen::Vector3d rotationVector(Eigen::Quaterniond q)
{
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    const double s2 = q.vec().squaredNorm(), w = q.w();
    if (s2 < 1e-6 * w * w) {
        const double inverseW = 1.0 / w, r2 = s2 * inverseW * inverseW;
        return (2.0 * inverseW * (1.0 - r2 / 3.0 + r2 * r2 / 5.0)) * q.vec();
    }
    const double s = std::sqrt(s2);
    return (2.0 * std::atan2(s, w) / s) * q.vec();
}

/// The rotation matrix of a quaternion of any length (its own normalised): one division, where
/// normalising first takes a root and four.
Eigen::Matrix3d rotationMatrixOf(const Eigen::Quaterniond& q)
{
    const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
    const double s = 2.0 / (w * w + x * x + y * y + z * z);
    const double xx = s * x * x, yy = s * y * y, zz = s * z * z, xy = s * x * y, xz = s * x * z, yz = s * y * z;
    const double wx = s * w * x, wy = s * w * y, wz = s * w * z;
    Eigen::Matrix3d r;
    r << 1.0 - yy - zz, xy - wz, xz + wy,
         xy + wz, 1.0 - xx - zz, yz - wx,
         xz - wy, yz + wx, 1.0 - xx - yy;
    return r;
}

}  // namespace

BondStrain Lattice::strainOf(const LatticeBond& bond) const
{
    const Eigen::Quaterniond& qa = state.orientation[bond.low];
    const Eigen::Quaterniond& qb = state.orientation[bond.high];
    BondStrain s;
    if (bond.pinned) {
        // A pin measures its voxel's centre in the held point's frame, across its axis only: the
        // voxel may turn on it and slide toward or away from the support (glazing's clearance).
        s.frame = rotationMatrixOf(mModel.held[bond.low] ? qa : qb);
        s.displacementM = s.frame.transpose() * (state.positionM[bond.high] - state.positionM[bond.low]);
        s.displacementM[bond.axis] = 0.0;
        return s;
    }
    // Half-way between two orientations: their normalised sum (slerp at ½, as qb is near qa).
    const double sameHemisphere = qa.coeffs().dot(qb.coeffs()) >= 0.0 ? 1.0 : -1.0;
    Eigen::Quaterniond half;
    half.coeffs() = qa.coeffs() + sameHemisphere * qb.coeffs();
    s.frame = rotationMatrixOf(half);
    s.displacementM = s.frame.transpose() * (state.positionM[bond.high] - state.positionM[bond.low]);
    s.displacementM[bond.axis] -= mModel.spacingM;
    s.rotationRad = s.frame.transpose() * rotationVector(qb * qa.conjugate());
    return s;
}

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
    terms.armM = state.positionM[bond.high] - state.positionM[bond.low];
    const double lengthM = terms.armM.norm();
    const Eigen::Vector3d along = terms.armM * (1.0 / lengthM);
    const double openingRateMS = (state.velocityMS[bond.high] - state.velocityMS[bond.low]).dot(along);
    const double damageBefore = bondDamage(b);
    double damage = damageBefore;
    if (growDamage && growBondDamage(b, equivalentStretchM(b, s, lengthM, damage), crushingShorteningM(b, s.displacementM[a]),
                                     std::abs(openingRateMS) / mModel.spacingM, dtS))
        damage = bondDamage(b);
    // Compression carries what crushing left (a crack in tension or shear closes on itself).
    const double crushed = crushingDamage(b), uncrushed = 1.0 - crushed;
    const bool broke = damage >= 1.0 && damageBefore < 1.0;
    // What a pin held is lost where it fails (the glazing's own dissipation).
    const bool snapped = broke && mModel.damageLaw == LatticeDamageLaw::Softening && snapsAtPeak(b) && !bond.pinned && crackingDamage(b) >= 1.0;
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
    const double rubbleM = crushed * overlapM - k.strength[bond.strengthClass].crushingEndShorteningM;
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

void Lattice::completeBondForce(size_t b)
{
    // The volumetric energy's force along the bond: d(Σ ½ λ h³ (tr ε)²) / d(length).
    const LatticeBond& bond = mModel.bonds[b];
    BondForceTerms& terms = mBondTerms[b];
    const double sharesPa = mVolumetricStressShare[bond.low][bond.axis] + mVolumetricStressShare[bond.high][bond.axis];
    terms.forceOnHighN -= (terms.volumetricAreaPerArmM * sharesPa) * terms.armM;
    // Read across its particles by the next substep's crushing (confinementPa).
    if (!mBondNormalStressPa.empty())
        mBondNormalStressPa[b] = -terms.forceOnHighN.dot(terms.armM) / (terms.armM.norm() * mModel.spacingM * mModel.spacingM);
    // The bond acts at the face between its particles: the pair's moment about either centre
    // is the same, -(arm / 2) × force. A pin acts at its voxel's centre (its other end is held).
    terms.pairMomentNm = bond.pinned ? Eigen::Vector3d::Zero() : Eigen::Vector3d(-0.5 * terms.armM.cross(terms.forceOnHighN));
}

void Lattice::gatherBondForces(size_t p)
{
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
    for (int face = 0; face < 6; ++face) {
        const int32_t b = mModel.bondAcross[p][face];
        if (b < 0) continue;
        const BondForceTerms& terms = mBondTerms[size_t(b)];
        if (face & 1) {  // the bond across p's +axis face: p is its low end
            force -= terms.forceOnHighN;
            moment += terms.pairMomentNm - terms.bendingMomentNm;
        } else {
            force += terms.forceOnHighN;
            moment += terms.pairMomentNm + terms.bendingMomentNm;
        }
    }
    state.bondForceN[p] = force;
    state.bondMomentNm[p] = moment;
}

}  // namespace spall
