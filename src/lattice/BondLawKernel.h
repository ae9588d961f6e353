// A bond's damage, force terms and failure index, written once for one bond (T = double: the
// bond pass's Lattice::measureBond) and for a batch of bonds side by side (T = an xsimd batch of
// doubles: the bonds whose damage does not grow in the step, BondStrainBatchImpl.h), so both
// round alike, bit for bit (issue 49). Like BondStrainKernel.h: no Eigen, and an unnamed namespace,
// since the batch translation units are compiled for wider instruction sets than the rest.
#pragma once

#include "BondStrainKernel.h"

#include <cmath>
#include <type_traits>

namespace spall {
namespace {
namespace bond_law {

using bond_strain::selectLanes;

/// max(0, v) as std::max(0.0, v) gives it: v where 0 < v, else +0.
template <typename T>
T positivePart(const T& v)
{
    return selectLanes(T(0.0) < v, v, T(0.0));
}

/// The frame times a vector, summed as Eigen's SSE2 code sums a 3 × 3 by a 3-vector (the first
/// two rows as a pair, left to right; the third alone, right first), as the lattice always has.
/// (Frame: anything read as frame[row][column]; for one bond, a lane of a run in place.)
template <typename Frame, typename T>
void frameTimes(const Frame& frame, const T (&v)[3], T (&out)[3])
{
    for (int i = 0; i < 2; ++i) out[i] = (frame[i][0] * v[0] + frame[i][1] * v[1]) + frame[i][2] * v[2];
    out[2] = frame[2][0] * v[0] + (frame[2][1] * v[1] + frame[2][2] * v[2]);
}

/// The spring's force on high and the bending and twisting moment, in the world, of a bond whose
/// stiffnesses are `intact` (1 − D) of its own: per component of its frame, the spring along
/// the axis and the shear across it (`springNPerM`), the twisting about the axis and the bending
/// about the others (`turnNmPerRad`). (Frame and Vector: read by [], as frameTimes.)
template <typename Frame, typename Vector, typename T>
void elasticTerms(const Frame& frame, const Vector& displacementM, const Vector& rotationRad, const T (&springNPerM)[3],
                  const T (&turnNmPerRad)[3], const T& intact, T (&forceOnHighN)[3], T (&momentNm)[3])
{
    // Negated by a product, which flips the sign bit of a zero as the scalar negation does
    // (BondStrainKernel.h's relativeRotation).
    const T minusIntact = intact * T(-1.0);
    T local[3], turn[3];
    for (int i = 0; i < 3; ++i) local[i] = (minusIntact * springNPerM[i]) * displacementM[i];
    for (int i = 0; i < 3; ++i) turn[i] = (minusIntact * turnNmPerRad[i]) * rotationRad[i];
    frameTimes(frame, local, forceOnHighN);
    frameTimes(frame, turn, momentNm);
}

/// Less the bulk viscosity's dashpot along the arm (`along`, a unit vector), its stiffness
/// `intact` of its own: ζ ρ c h² times the opening rate (LatticeModel::bulkViscosity).
template <typename T>
void subtractDashpot(const T& intact, double bulkViscosity, double dashpotPerViscosityNSPerM, const T& openingRateMS, const T (&along)[3],
                     T (&forceOnHighN)[3])
{
    const T forceN = intact * T(bulkViscosity) * T(dashpotPerViscosityNSPerM) * openingRateMS;
    for (int i = 0; i < 3; ++i) forceOnHighN[i] = forceOnHighN[i] - forceN * along[i];
}

/// Damage on a linear softening line from u0 to uf at the driver κ: the secant stiffness
/// (1 − D) κ / u0 = (uf − κ) / (uf − u0) (Bažant & Oh 1983's crack band, linear).
template <typename T>
T lineDamage(const T& kappa, const T& u0, const T& uf)
{
    // One bond: most are before their peak, and need no division.
    if constexpr (std::is_same_v<T, double>)
        if (kappa <= u0) return 0.0;
    const T onLine = T(1.0) - (u0 / kappa) * (uf - kappa) / (uf - u0);
    return selectLanes(kappa <= u0, T(0.0), selectLanes(kappa >= uf, T(1.0), onLine));
}

/// A bond's damage, 1 − (1 − D_t)(1 − D_c), from D_t (cracking) and D_c (crushing); without
/// crushing exactly D_t (1 − (1 − D_t) need not round back to it).
template <typename T>
T combinedDamage(const T& cracked, const T& crushed)
{
    return selectLanes(crushed == T(0.0), cracked, T(1.0) - (T(1.0) - cracked) * (T(1.0) - crushed));
}

/// What a bond's laws give the force pass (Lattice::BondForceTerms and BondStretch).
template <typename T>
struct BondTerms {
    T forceOnHighN[3], momentNm[3];
    T effectiveStretchM, uncrushedStretchM, volumetricAreaPerArmM;
};

/// What the terms take from the bond's strain besides its frame, displacement and rotation.
template <typename T>
struct ArmState {
    T along[3], lengthM, openingRateMS;
};

/// What the terms take from the bond's stiffness and strength: the springs and turns as
/// elasticTerms takes them, its normal spring, and where crushing's softening line ends.
template <typename T>
struct TermConstants {
    T springNPerM[3], turnNmPerRad[3], normalNPerM, crushingEndShorteningM;
};

/// A bond's terms at damage `damage` (D), of which crushing's is `crushed` (D_c), for a bond of
/// rest length `spacingM` (Lattice::BondForceTerms, BondStretch): the springs and turns carry
/// 1 − D of their stiffness; what cracking took still carries compression, as contact, along the
/// line of centres while the cubes overlap (in the bond's frame it would push apart particles
/// that slid past each other or turned over, which feeds energy into a shattered lattice); the
/// crushed part's rubble carries again once squeezed past its softening line's end, k (D_c
/// overlap − uf), growing with D_c from nothing so no force jumps in; the dashpot softens with
/// the spring (1 − D opening, 1 − D_c closing: a crack carries no viscous stress). The stretch
/// and the volumetric area take √(1 − D) opening and √(1 − D_c) closing, so the bond's
/// volumetric share falls as its spring does.
template <typename Frame, typename Vector, typename T>
BondTerms<T> bondTerms(const Frame& frame, const Vector& displacementM, const Vector& rotationRad, const ArmState<T>& arm, const TermConstants<T>& k,
                       const T& damage, const T& crushed, double spacingM, double bulkViscosity, double dashpotPerViscosityNSPerM)
{
    using std::sqrt;
    BondTerms<T> out;
    const T intact = T(1.0) - damage, uncrushed = T(1.0) - crushed;
    elasticTerms(frame, displacementM, rotationRad, k.springNPerM, k.turnNmPerRad, intact, out.forceOnHighN, out.momentNm);
    const T overlapM = T(spacingM) - arm.lengthM;
    // Added only where they act (x + 0 would turn a −0 into +0).
    const auto inContact = intact < uncrushed && overlapM > T(0.0);
    const T contactN = (uncrushed - intact) * k.normalNPerM * overlapM;
    const T rubbleM = crushed * overlapM - k.crushingEndShorteningM;
    const auto onRubble = crushed > T(0.0) && rubbleM > T(0.0);
    const T rubbleN = k.normalNPerM * rubbleM;
    for (int i = 0; i < 3; ++i) {
        out.forceOnHighN[i] = selectLanes(inContact, out.forceOnHighN[i] + contactN * arm.along[i], out.forceOnHighN[i]);
        out.forceOnHighN[i] = selectLanes(onRubble, out.forceOnHighN[i] + rubbleN * arm.along[i], out.forceOnHighN[i]);
    }
    const auto opening = arm.lengthM > T(spacingM);
    if (bulkViscosity > 0.0)
        subtractDashpot(selectLanes(opening, intact, uncrushed), bulkViscosity, dashpotPerViscosityNSPerM, arm.openingRateMS, arm.along, out.forceOnHighN);
    const T sqrtIntact = sqrt(intact), sqrtUncrushed = selectLanes(crushed == T(0.0), T(1.0), sqrt(uncrushed));
    const T stretchM = arm.lengthM - T(spacingM);
    out.uncrushedStretchM = selectLanes(opening, sqrtIntact * stretchM, stretchM);
    out.effectiveStretchM = selectLanes(opening, out.uncrushedStretchM, sqrtUncrushed * out.uncrushedStretchM);
    out.volumetricAreaPerArmM = selectLanes(opening, sqrtIntact, sqrtUncrushed) * T(spacingM) * T(spacingM) / arm.lengthM;
    return out;
}

/// bondTerms at D = D_c = 0, without the terms that are then nothing (the same bits: 1 × x = x,
/// √1 = 1, and no contact, rubble or softening).
template <typename Frame, typename Vector, typename T>
BondTerms<T> intactBondTerms(const Frame& frame, const Vector& displacementM, const Vector& rotationRad, const ArmState<T>& arm,
                             const TermConstants<T>& k, double spacingM, double bulkViscosity, double dashpotPerViscosityNSPerM)
{
    BondTerms<T> out;
    const T one(1.0);
    elasticTerms(frame, displacementM, rotationRad, k.springNPerM, k.turnNmPerRad, one, out.forceOnHighN, out.momentNm);
    if (bulkViscosity > 0.0) subtractDashpot(one, bulkViscosity, dashpotPerViscosityNSPerM, arm.openingRateMS, arm.along, out.forceOnHighN);
    out.effectiveStretchM = out.uncrushedStretchM = arm.lengthM - T(spacingM);
    out.volumetricAreaPerArmM = T(spacingM * spacingM) / arm.lengthM;
    return out;
}

/// The shear index of a bond whose shear springs are equal across its axis `a`: k_s |d across a| /
/// (h² c), from the components' squares summed left to right.
template <typename T>
T isotropicShearIndex(const T& shearIndexPerM, const T (&displacementM)[3], const T& normalM)
{
    using std::sqrt;
    const T squaredNorm = displacementM[0] * displacementM[0] + displacementM[1] * displacementM[1] + displacementM[2] * displacementM[2];
    return shearIndexPerM * sqrt(positivePart(squaredNorm - normalM * normalM));
}

/// What the failure index takes from a bond's strength class and axis (LatticeModel::FailureTerms).
template <typename T>
struct FailureTerms {
    T peakStretchM, tensionIndexPerM, normalIndexPerM, indexPerPa, frictionCoefficient;
};

/// The failure index (Lattice::equivalentStretchM says why each term) in tension, the stretch
/// with bending's (`stretchM`) not negative: Mohr–Coulomb's tension cut-off and shear together.
template <typename T>
T failureIndexInTension(const T& stretchM, const T& shearIndex, const FailureTerms<T>& terms)
{
    using std::sqrt;
    const T tensionIndex = stretchM * terms.tensionIndexPerM;
    return sqrt(tensionIndex * tensionIndex + shearIndex * shearIndex);
}

/// In compression: the shear less the friction on the compression across the bond, its
/// spring's and its particles' volumetric shares (`sharesPa`, low's plus high's).
template <typename T>
T failureIndexInCompression(const T& normalM, const T& shearIndex, const T& sharesPa, const FailureTerms<T>& terms)
{
    const T normalIndex = terms.normalIndexPerM * normalM + terms.indexPerPa * sharesPa;
    return positivePart(shearIndex - terms.frictionCoefficient * positivePart(normalIndex * T(-1.0)));
}

/// The stretch at the face's most stretched corner that bending adds (Lattice::equivalentStretchM):
/// h/2 (1 − D) times the turns about the two axes across the bond's.
template <typename T>
T bendingStretchM(double spacingM, const T& intact, const T& turnAcrossRad, const T& otherTurnAcrossRad)
{
    using std::abs;
    return T(0.5 * spacingM) * intact * (abs(turnAcrossRad) + abs(otherTurnAcrossRad));
}

}  // namespace bond_law
}  // namespace
}  // namespace spall
