// A bond's elastic terms and failure index, written once for one bond (T = double: the bond
// pass's Lattice::measureBond) and for a batch of bonds side by side (T = an xsimd batch of
// doubles: the bonds that stay on their elastic line, BondStrainBatchImpl.h), so both round
// alike, bit for bit (issue 49). Like BondStrainKernel.h: no Eigen, and an unnamed namespace,
// since the batch translation units are compiled for wider instruction sets than the rest.
#pragma once

#include "BondStrainKernel.h"

#include <cmath>

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

/// The shear index of a bond whose shear springs are equal across its axis `a`: k_s |d across a| /
/// (h² c), from the components' squares summed left to right.
template <typename T>
T isotropicShearIndex(const T& shearIndexPerM, const T (&displacementM)[3], const T& normalM)
{
    using std::sqrt;
    const T squaredNorm = displacementM[0] * displacementM[0] + displacementM[1] * displacementM[1] + displacementM[2] * displacementM[2];
    return shearIndexPerM * sqrt(positivePart(squaredNorm - normalM * normalM));
}

/// What the failure index takes from a bond's strength class and axis (LatticeModel::FailureTerms;
/// the caller scales the index by its peak stretch).
template <typename T>
struct FailureTerms {
    T tensionIndexPerM, normalIndexPerM, indexPerPa, frictionCoefficient;
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
