// measureBondStrains: the widest batch this machine runs (xsimd's dispatch), and the SSE2 batch
// every x86-64 has, compiled here with the project's own flags.
#include "BondStrainBatchImpl.h"

namespace spall {

using BondStrainArchitectures = xsimd::arch_list<xsimd::avx512f, xsimd::avx2, xsimd::sse2>;

extern template void MeasureBondStrains::operator()<xsimd::avx512f>(xsimd::avx512f, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;
extern template void MeasureBondStrains::operator()<xsimd::avx2>(xsimd::avx2, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;
template void MeasureBondStrains::operator()<xsimd::sse2>(xsimd::sse2, const BondStrainInputs&, size_t, size_t, BondStrainRun&) const;

void measureBondStrains(const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out)
{
    // The machine's instruction sets are asked once.
    static auto dispatched = xsimd::dispatch<BondStrainArchitectures>(MeasureBondStrains{});
    dispatched(in, first, count, out);
}

bool machineRuns(BondStrainInstructions set)
{
    const auto available = xsimd::available_architectures();
    switch (set) {
    case BondStrainInstructions::Sse2: return available.sse2;
    case BondStrainInstructions::Avx2: return available.avx2;
    case BondStrainInstructions::Avx512: return available.avx512f;
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

}  // namespace spall
