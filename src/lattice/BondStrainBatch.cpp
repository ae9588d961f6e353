// measureBondStrains: the widest batch this machine runs, and the SSE2 batch every x86-64 has,
// compiled here with the project's own flags. Chosen by libgcc's __builtin_cpu_supports, which
// also asks whether the operating system saves the wider registers (xsimd 8.1's check reads the
// processor's bits alone, and a kernel may switch AVX off).
#include "BondStrainBatchImpl.h"

namespace spall {

extern template void MeasureBondStrains::operator()<xsimd::avx512f>(xsimd::avx512f, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;
extern template void MeasureBondStrains::operator()<xsimd::avx2>(xsimd::avx2, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;
template void MeasureBondStrains::operator()<xsimd::sse2>(xsimd::sse2, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;

bool machineRuns(BondStrainInstructions set)
{
    switch (set) {
    case BondStrainInstructions::Sse2: return __builtin_cpu_supports("sse2");
    case BondStrainInstructions::Avx2: return __builtin_cpu_supports("avx2");
    case BondStrainInstructions::Avx512: return __builtin_cpu_supports("avx512f");
    }
    return false;
}

void measureBondStrainsWith(BondStrainInstructions set, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out)
{
    const MeasureBondStrains measure;
    switch (set) {
    case BondStrainInstructions::Sse2: return measure(xsimd::sse2{}, in, first, count, out);
    case BondStrainInstructions::Avx2: return measure(xsimd::avx2{}, in, first, count, out);
    case BondStrainInstructions::Avx512: return measure(xsimd::avx512f{}, in, first, count, out);
    }
}

void measureBondStrains(const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out)
{
    // The machine is asked once.
    static const BondStrainInstructions widest = machineRuns(BondStrainInstructions::Avx512) ? BondStrainInstructions::Avx512
                                                 : machineRuns(BondStrainInstructions::Avx2) ? BondStrainInstructions::Avx2
                                                                                             : BondStrainInstructions::Sse2;
    measureBondStrainsWith(widest, in, first, count, out);
}

}  // namespace spall
