// measureBondStrains for AVX2 (four doubles a batch); compiled with -mavx2 and without FMA
// contraction, so it rounds as the scalar code does (CMakeLists.txt).
#include "BondStrainBatchImpl.h"

namespace spall {
template void MeasureBondStrains::operator()<xsimd::avx2>(xsimd::avx2, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;
}
