// measureBondStrains for AVX-512 (eight doubles a batch); compiled with -mavx512f and without
// FMA contraction, so it rounds as the scalar code does (CMakeLists.txt).
#include "BondStrainBatchImpl.h"

namespace spall {
template void MeasureBondStrains::operator()<xsimd::avx512f>(xsimd::avx512f, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;
}
