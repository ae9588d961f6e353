// The bond pass's strain measurement for a run of consecutive bonds at once, in batches as wide
// as the machine's vector registers (xsimd; AVX-512, AVX2 or SSE2, chosen at run time), the
// same formulas as one bond's (BondStrainKernel.h), bit for bit; and, for the bonds that stay on
// their elastic line, their laws' terms too (BondLawKernel.h).
#pragma once

#include <cstddef>
#include <cstdint>

namespace spall {

/// What the laws of a bond take from its strength class and axis: one row per class and axis
/// (class × 3 + axis), all doubles, so a batch gathers a field by one index. (Read only for the
/// rows that batch.)
struct BondLawRow {
    /// Per component of the bond's frame: the normal spring along its axis, the shear springs
    /// across it (unit: N/m); the twisting stiffness about its axis, the bending about the
    /// others (unit: N m/rad).
    double springNPerM[3], turnNmPerRad[3];
    /// LatticeModel::FailureTerms, the shear index's the same across both directions; its
    /// peak stretch is also the softening line's (Strength::peakStretchM).
    double peakStretchM, tensionIndexPerM, shearIndexPerM, normalIndexPerM, indexPerPa, frictionCoefficient;
    /// Crushing (Strength): fc (0: never), its peak shortening, d (LatticeStiffness::normalModulusPa).
    double compressiveStrengthPa, crushingPeakShorteningM, normalModulusPa;
    /// The softening line's end, where it carries nothing (Strength::zeroTractionStretchM).
    double zeroTractionStretchM;
    /// 1 where a batch may measure the class's bonds along the axis (shear isotropic across
    /// the axis), else 0: they are measured one at a time.
    double batches;
};

static_assert(sizeof(BondLawRow) == 17 * sizeof(double), "a row is doubles alone");

/// Where BondHistory's fields lie among its doubles (LatticeBonds.cpp checks them).
enum BondHistoryWord : size_t { kStrengthScaleWord = 0, kMaxEquivalentStretchWord = 1, kStrengthFactorWord = 2, kMaxCrushingWord = 5, kHistoryWords = 6 };

/// What the elastic bonds' laws read besides the strains (LatticeBonds.cpp's measureBonds):
/// the rows, the bonds' histories, the particles' volumetric stress shares (3 a particle) and,
/// for a material that crushes, their uncrushed λ tr ε (1 a particle; else null) (unit: Pa).
struct BondLawInputs {
    const BondLawRow* rows = nullptr;
    const double* history = nullptr;
    const double* volumetricStressSharePa = nullptr;
    const double* uncrushedLambdaTracePa = nullptr;
    double bulkViscosity = 0.0, dashpotPerViscosityNSPerM = 0.0;
};

/// The particles' state as flat arrays and the bonds' ends: positions and velocities 3 doubles a
/// particle, orientations 4 (x, y, z, w), bonds 4 words each (LatticeBond: low, high, axis, the
/// rest).
struct BondStrainInputs {
    const double* positionM = nullptr;
    const double* velocityMS = nullptr;
    const double* quaternion = nullptr;
    const uint32_t* bondWords = nullptr;
    double spacingM = 0.0;
    /// Given, the batches also find the bonds whose damage stays as it is (BondStrainRun::steady).
    const BondLawInputs* laws = nullptr;
};

/// The strains of up to kCapacity consecutive bonds, structure of arrays (BondStrainKernel.h's
/// Strain, lane by lane).
struct BondStrainRun {
    static constexpr size_t kCapacity = 64;  ///< a multiple of every batch width
    alignas(64) double frame[3][3][kCapacity];
    alignas(64) double displacementM[3][kCapacity];
    alignas(64) double rotationRad[3][kCapacity];
    alignas(64) double armM[3][kCapacity];
    alignas(64) double lengthM[kCapacity];
    alignas(64) double openingRateMS[kCapacity];
    /// 1 where the rotation's series held; 0 where the bond must be measured alone.
    alignas(64) double smallTurn[kCapacity];
    /// With BondStrainInputs::laws: 1 where a bond's damage stays as it is this step, so it
    /// answers on its elastic line or, cracked, on its secant, and its terms below are all its
    /// laws give (Lattice::measureBond's): its turn small, not a pin, its class batched, its
    /// crushing damage 0, and neither its failure index nor its crushing past the largest so
    /// far; else 0.
    alignas(64) double steady[kCapacity];
    alignas(64) double forceOnHighN[3][kCapacity];     ///< its spring, closed crack and dashpot (unit: N)
    alignas(64) double bendingMomentNm[3][kCapacity];  ///< on high (unit: N m)
    alignas(64) double stretchM[kCapacity];            ///< BondStretch's, both alike uncrushed (unit: m)
    alignas(64) double volumetricAreaPerArmM[kCapacity];  ///< BondForceTerms's (unit: m)
};

/// Measures bonds first … first + count − 1 (count ≤ kCapacity) into `out`, lane i for bond
/// first + i, with the widest instruction set this machine runs. Pinned bonds are measured as
/// if they were not (their callers measure them alone).
void measureBondStrains(const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out);

/// The instruction sets the batches are compiled for, narrowest first.
enum class BondStrainInstructions { Sse2, Avx2, Avx512 };
/// Whether this machine runs them.
bool machineRuns(BondStrainInstructions set);
/// measureBondStrains with a given set, which the machine must run (the tests compare them).
void measureBondStrainsWith(BondStrainInstructions set, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out);

}  // namespace spall
