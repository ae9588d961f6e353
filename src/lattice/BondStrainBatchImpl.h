// The body of measureBondStrains for one instruction set, included by the one translation unit
// compiled for it (BondStrainBatch*.cpp).
#pragma once

#include "BondStrainBatch.h"
#include "BondStrainKernel.h"

#include <xsimd/xsimd.hpp>

#include <immintrin.h>

#include <algorithm>
#include <type_traits>

namespace spall {

/// base[offsets[i]] in lane i. By the instruction set's own gather: xsimd 8.1's batch::gather
/// misses its AVX2 and AVX-512 versions for doubles and falls back to inserting lane by lane.
template <class Arch>
xsimd::batch<double, Arch> gatherDoubles(const double* base, const int64_t* offsets)
{
    if constexpr (std::is_same_v<Arch, xsimd::avx512f>)
        return _mm512_i64gather_pd(_mm512_load_si512(offsets), base, sizeof(double));
    else if constexpr (std::is_same_v<Arch, xsimd::avx2>)
        return _mm256_i64gather_pd(base, _mm256_load_si256(reinterpret_cast<const __m256i*>(offsets)), sizeof(double));
    else
        return _mm_set_pd(base[offsets[1]], base[offsets[0]]);
}

struct MeasureBondStrains {
    template <class Arch>
    void operator()(Arch, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out) const;
};

template <class Arch>
void MeasureBondStrains::operator()(Arch, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out) const
{
    using Batch = xsimd::batch<double, Arch>;
    constexpr size_t width = Batch::size;
    static_assert(BondStrainRun::kCapacity % width == 0, "a run holds whole batches");
    for (size_t lane0 = 0; lane0 < count; lane0 += width) {
        // Where each end's position (and velocity) and orientation start in the flat arrays.
        alignas(64) int64_t low3[width], high3[width], low4[width], high4[width];
        alignas(64) double axis[width];
        for (size_t i = 0; i < width; ++i) {
            // Past the run's end, the last bond again (its results land beyond count, unread).
            const uint32_t* words = in.bondWords + 4 * (first + std::min(lane0 + i, count - 1));
            low3[i] = 3 * int64_t(words[0]), high3[i] = 3 * int64_t(words[1]);
            low4[i] = 4 * int64_t(words[0]), high4[i] = 4 * int64_t(words[1]);
            axis[i] = double(int32_t(words[2]));
        }
        bond_strain::EndState<Batch> a, b;
        for (int k = 0; k < 3; ++k) {
            a.position[k] = gatherDoubles<Arch>(in.positionM + k, low3), b.position[k] = gatherDoubles<Arch>(in.positionM + k, high3);
            a.velocity[k] = gatherDoubles<Arch>(in.velocityMS + k, low3), b.velocity[k] = gatherDoubles<Arch>(in.velocityMS + k, high3);
        }
        for (int k = 0; k < 4; ++k)
            a.quaternion[k] = gatherDoubles<Arch>(in.quaternion + k, low4), b.quaternion[k] = gatherDoubles<Arch>(in.quaternion + k, high4);
        bond_strain::Strain<Batch> s;
        typename Batch::batch_bool_type small;
        bond_strain::halfwayStrain(a, b, Batch::load_aligned(axis), in.spacingM, s, small);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) s.frame[r][c].store_aligned(&out.frame[r][c][lane0]);
        for (int k = 0; k < 3; ++k) {
            s.displacementM[k].store_aligned(&out.displacementM[k][lane0]);
            s.rotationRad[k].store_aligned(&out.rotationRad[k][lane0]);
            s.armM[k].store_aligned(&out.armM[k][lane0]);
        }
        s.lengthM.store_aligned(&out.lengthM[lane0]);
        s.openingRateMS.store_aligned(&out.openingRateMS[lane0]);
        xsimd::select(small, Batch(1.0), Batch(0.0)).store_aligned(&out.smallTurn[lane0]);
    }
}

}  // namespace spall
