// The bond pass's strain measurement for a run of consecutive bonds at once, in batches as wide
// as the machine's vector registers (xsimd; AVX-512, AVX2 or SSE2, chosen at run time), the
// same formulas as one bond's (BondStrainKernel.h), bit for bit.
#pragma once

#include <cstddef>
#include <cstdint>

namespace spall {

/// The particles' state as flat arrays and the bonds' ends: positions and velocities 3 doubles a
/// particle, orientations 4 (x, y, z, w), bonds 4 words each (LatticeBond: low, high, axis, the
/// rest).
struct BondStrainInputs {
    const double* positionM = nullptr;
    const double* velocityMS = nullptr;
    const double* quaternion = nullptr;
    const uint32_t* bondWords = nullptr;
    double spacingM = 0.0;
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
