// The body of measureBondStrains for one instruction set, included by the one translation unit
// compiled for it (BondStrainBatch*.cpp).
#pragma once

#include "BondStrainBatch.h"
#include "BondStrainKernel.h"

#include <xsimd/xsimd.hpp>

#include <algorithm>
#include <type_traits>

namespace spall {

struct MeasureBondStrains {
    template <class Arch>
    void operator()(Arch, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out) const;
};

template <class Arch>
void MeasureBondStrains::operator()(Arch, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out) const
{
    using Batch = xsimd::batch<double, Arch>;
    using Index = xsimd::batch<int64_t, Arch>;
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
        const Index atLow3 = Index::load_aligned(low3), atHigh3 = Index::load_aligned(high3);
        const Index atLow4 = Index::load_aligned(low4), atHigh4 = Index::load_aligned(high4);
        bond_strain::EndState<Batch> a, b;
        for (int k = 0; k < 3; ++k) {
            a.position[k] = Batch::gather(in.positionM + k, atLow3), b.position[k] = Batch::gather(in.positionM + k, atHigh3);
            a.velocity[k] = Batch::gather(in.velocityMS + k, atLow3), b.velocity[k] = Batch::gather(in.velocityMS + k, atHigh3);
        }
        for (int k = 0; k < 4; ++k)
            a.quaternion[k] = Batch::gather(in.quaternion + k, atLow4), b.quaternion[k] = Batch::gather(in.quaternion + k, atHigh4);
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
