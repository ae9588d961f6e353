// The body of measureBondStrains for one instruction set, included by the one translation unit
// compiled for it (BondStrainBatch*.cpp).
#pragma once

#include "BondStrainBatch.h"
#include "BondLawKernel.h"
#include "BondStrainKernel.h"

#include <xsimd/xsimd.hpp>

#include <immintrin.h>

#include <algorithm>
#include <cstddef>
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
        return _mm256_set_pd(base[offsets[3]], base[offsets[2]], base[offsets[1]], base[offsets[0]]);
    else
        return _mm_set_pd(base[offsets[1]], base[offsets[0]]);
}

/// The 3-vectors starting at base[offsets[i]], one batch per component. By the instruction set's
/// gathers on AVX-512; on AVX2 by plain loads turned into lanes (two pairs of (x, y) unpacked, z
/// lane by lane), since AMD's Zen runs a four-lane gather as about nine operations, several times
/// the loads' cost (the bond pass spent most of its strain batches in them, issue 49).
template <class Arch>
void gatherTriples(const double* base, const int64_t* offsets, xsimd::batch<double, Arch> (&out)[3])
{
    if constexpr (std::is_same_v<Arch, xsimd::avx2>) {
        const __m256d xy02 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(base + offsets[0])), _mm_loadu_pd(base + offsets[2]), 1);
        const __m256d xy13 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(base + offsets[1])), _mm_loadu_pd(base + offsets[3]), 1);
        out[0] = _mm256_unpacklo_pd(xy02, xy13);
        out[1] = _mm256_unpackhi_pd(xy02, xy13);
        out[2] = _mm256_set_pd(base[offsets[3] + 2], base[offsets[2] + 2], base[offsets[1] + 2], base[offsets[0] + 2]);
    } else {
        for (int k = 0; k < 3; ++k) out[k] = gatherDoubles<Arch>(base + k, offsets);
    }
}

/// The four doubles starting at base[offsets[i]] (a quaternion, four fields of a record), one
/// batch per word: on AVX2 four loads and a 4 × 4 transpose (gatherTriples says why).
template <class Arch>
void gatherQuads(const double* base, const int64_t* offsets, xsimd::batch<double, Arch>* out)
{
    if constexpr (std::is_same_v<Arch, xsimd::avx2>) {
        const __m256d q0 = _mm256_loadu_pd(base + offsets[0]), q1 = _mm256_loadu_pd(base + offsets[1]);
        const __m256d q2 = _mm256_loadu_pd(base + offsets[2]), q3 = _mm256_loadu_pd(base + offsets[3]);
        const __m256d xz01 = _mm256_unpacklo_pd(q0, q1), yw01 = _mm256_unpackhi_pd(q0, q1);
        const __m256d xz23 = _mm256_unpacklo_pd(q2, q3), yw23 = _mm256_unpackhi_pd(q2, q3);
        out[0] = _mm256_permute2f128_pd(xz01, xz23, 0x20);
        out[1] = _mm256_permute2f128_pd(yw01, yw23, 0x20);
        out[2] = _mm256_permute2f128_pd(xz01, xz23, 0x31);
        out[3] = _mm256_permute2f128_pd(yw01, yw23, 0x31);
    } else {
        for (int k = 0; k < 4; ++k) out[k] = gatherDoubles<Arch>(base + k, offsets);
    }
}

struct MeasureBondStrains {
    template <class Arch>
    void operator()(Arch, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out) const;
};

/// Where a batch's bonds' data lie in the flat arrays, lane by lane (past the run's end, the
/// last bond again: its results land beyond count, unread).
template <size_t width>
struct LaneOffsets {
    alignas(64) int64_t low3[width], high3[width], low4[width], high4[width];
    alignas(64) int64_t low[width], high[width], lowShare[width], highShare[width], history[width], row[width];
    alignas(64) double axis[width], pinned[width];

    LaneOffsets(const BondStrainInputs& in, size_t first, size_t count, size_t lane0)
    {
        constexpr int64_t rowWords = sizeof(BondLawRow) / sizeof(double);
        for (size_t i = 0; i < width; ++i) {
            const size_t b = first + std::min(lane0 + i, count - 1);
            const uint32_t* words = in.bondWords + 4 * b;
            const int64_t axisOf = int32_t(words[2]);
            low[i] = words[0], high[i] = words[1];
            low3[i] = 3 * low[i], high3[i] = 3 * high[i];
            low4[i] = 4 * low[i], high4[i] = 4 * high[i];
            lowShare[i] = low3[i] + axisOf, highShare[i] = high3[i] + axisOf;
            history[i] = int64_t(kHistoryWords * b);
            // LatticeBond's last word: its strength class, then whether it is a pin.
            row[i] = (3 * int64_t(words[3] & 0xffu) + axisOf) * rowWords;
            axis[i] = double(axisOf);
            pinned[i] = double((words[3] >> 8) & 0xffu);
        }
    }
};

/// Each lane's row of its laws (BondLawRow), a batch per field, read four fields at a time.
template <class Arch>
struct LaneRows {
    static constexpr size_t kWords = sizeof(BondLawRow) / sizeof(double), kQuads = kWords / 4;
    xsimd::batch<double, Arch> word[kWords];

    template <size_t width>
    LaneRows(const BondLawInputs& laws, const LaneOffsets<width>& at)
    {
        const double* rows = reinterpret_cast<const double*>(laws.rows);
        for (size_t quad = 0; quad < kQuads; ++quad) gatherQuads<Arch>(rows + 4 * quad, at.row, word + 4 * quad);
        for (size_t w = 4 * kQuads; w < kWords; ++w) word[w] = gatherDoubles<Arch>(rows + w, at.row);
    }
    /// The field at `offsetInRow` (offsetof(BondLawRow, field)).
    const xsimd::batch<double, Arch>& operator()(size_t offsetInRow) const { return word[offsetInRow / sizeof(double)]; }
};

/// c where the axis is 0, d where it is 1, e where it is 2.
template <class Batch>
Batch byAxis(const Batch& axis, const Batch& c, const Batch& d, const Batch& e)
{
    return xsimd::select(axis == Batch(0.0), c, xsimd::select(axis == Batch(1.0), d, e));
}

/// A batch's bonds whose damage stays as it is this step (BondStrainRun::steady), and their
/// 1 − D.
template <class Batch>
struct SteadyBonds {
    typename Batch::batch_bool_type steady;
    Batch intact;
};

/// Cracking's damage from the largest driver so far, as bond_laws::softeningDamage finds it:
/// 0 up to the line's peak u0; past it 1 where the class snaps at its peak, else the linear
/// softening line's secant damage up to its end uf (Bažant & Oh 1983's crack band).
template <class Batch>
Batch crackingDamage(const Batch& maxEquivalentM, const Batch& strengthScale, const Batch& peakStretchM, const Batch& zeroTractionStretchM)
{
    const Batch u0 = strengthScale * peakStretchM, kappa = maxEquivalentM;
    if (xsimd::all(kappa <= u0)) return Batch(0.0);  // most batches: no bond past its peak, no division
    const Batch uf = zeroTractionStretchM / strengthScale;
    const Batch onLine = Batch(1.0) - (u0 / kappa) * (uf - kappa) / (uf - u0);
    const auto broken = kappa >= uf || zeroTractionStretchM <= peakStretchM;
    return xsimd::select(kappa <= u0, Batch(0.0), xsimd::select(broken, Batch(1.0), onLine));
}

/// Which of a batch's bonds keep their damage this step, as Lattice::measureBond finds them: not
/// crushed, with neither their failure index (equivalentStretchM, bending's share softened with
/// the bond) nor their crushing (crushingShorteningM, where even unconfined it passes the largest
/// so far) growing.
template <class Arch, size_t width>
SteadyBonds<xsimd::batch<double, Arch>> steadyBonds(const BondLawInputs& laws, const LaneOffsets<width>& at, const LaneRows<Arch>& field,
                                                    const bond_strain::Strain<xsimd::batch<double, Arch>>& s, double spacingM)
{
    using Batch = xsimd::batch<double, Arch>;
    const Batch axis = Batch::load_aligned(at.axis);
    static_assert(kStrengthScaleWord < 4 && kMaxEquivalentStretchWord < 4 && kStrengthFactorWord < 4 && kMaxCrushingWord >= 4);
    Batch history[4];
    gatherQuads<Arch>(laws.history, at.history, history);
    const Batch scale = history[kStrengthScaleWord], maxEquivalentM = history[kMaxEquivalentStretchWord];
    const Batch maxCrushingM = gatherDoubles<Arch>(laws.history + kMaxCrushingWord, at.history);
    const Batch peakStretchM = field(offsetof(BondLawRow, peakStretchM)), crushingPeakM = field(offsetof(BondLawRow, crushingPeakShorteningM));
    const Batch intact = Batch(1.0) - crackingDamage(maxEquivalentM, scale * history[kStrengthFactorWord], peakStretchM,
                                                     field(offsetof(BondLawRow, zeroTractionStretchM)));
    const Batch normalM = byAxis(axis, s.displacementM[0], s.displacementM[1], s.displacementM[2]);
    const Batch stretchM = (s.lengthM - Batch(spacingM)) +
                           bond_law::bendingStretchM(spacingM, intact, byAxis(axis, s.rotationRad[1], s.rotationRad[2], s.rotationRad[0]),
                                                     byAxis(axis, s.rotationRad[2], s.rotationRad[0], s.rotationRad[1]));
    const Batch shearIndex = bond_law::isotropicShearIndex(field(offsetof(BondLawRow, shearIndexPerM)), s.displacementM, normalM);
    const Batch sharesPa = gatherDoubles<Arch>(laws.volumetricStressSharePa, at.lowShare) + gatherDoubles<Arch>(laws.volumetricStressSharePa, at.highShare);
    const bond_law::FailureTerms<Batch> terms{field(offsetof(BondLawRow, tensionIndexPerM)), field(offsetof(BondLawRow, normalIndexPerM)),
                                              field(offsetof(BondLawRow, indexPerPa)), field(offsetof(BondLawRow, frictionCoefficient))};
    const Batch equivalentM = xsimd::select(stretchM >= Batch(0.0), bond_law::failureIndexInTension(stretchM, shearIndex, terms),
                                            bond_law::failureIndexInCompression(normalM, shearIndex, sharesPa, terms)) *
                              peakStretchM;
    // Crushing's damage 0: the largest shortening so far not past its line's peak.
    const auto uncrushed = maxCrushingM <= Batch(0.0) || maxCrushingM <= scale * crushingPeakM;
    typename Batch::batch_bool_type crushingGrows(false);
    if (laws.uncrushedLambdaTracePa) {
        const Batch fcPa = field(offsetof(BondLawRow, compressiveStrengthPa));
        const Batch lambdaTracesPa = gatherDoubles<Arch>(laws.uncrushedLambdaTracePa, at.low) + gatherDoubles<Arch>(laws.uncrushedLambdaTracePa, at.high);
        const Batch compressionPa = (field(offsetof(BondLawRow, normalModulusPa)) * normalM / Batch(spacingM) + Batch(0.5) * lambdaTracesPa) * Batch(-1.0);
        crushingGrows = fcPa > Batch(0.0) && normalM < Batch(0.0) && compressionPa > Batch(0.0) && compressionPa / fcPa * crushingPeakM > maxCrushingM;
    }
    return {field(offsetof(BondLawRow, batches)) != Batch(0.0) && Batch::load_aligned(at.pinned) == Batch(0.0) && uncrushed &&
                equivalentM <= maxEquivalentM && !crushingGrows,
            intact};
}

/// The terms of a batch's bonds whose damage stays (Lattice::measureBond's, uncrushed, 1 − D
/// `intact`), lanes lane0 … of `out`: the springs softened by 1 − D; where a crack has closed,
/// the contact across it, (D k_n) times the overlap along the arm; the dashpot softened with the
/// spring while the bond opens; the stretch and volumetric area times √(1 − D) while it opens.
template <class Arch>
void storeSteadyTerms(const BondLawInputs& laws, const LaneRows<Arch>& field, const xsimd::batch<double, Arch>& axis,
                      const xsimd::batch<double, Arch>& intact, const bond_strain::Strain<xsimd::batch<double, Arch>>& s, double spacingM,
                      size_t lane0, BondStrainRun& out)
{
    using Batch = xsimd::batch<double, Arch>;
    Batch springNPerM[3], turnNmPerRad[3], forceOnHighN[3], momentNm[3];
    for (size_t k = 0; k < 3; ++k) {
        springNPerM[k] = field(offsetof(BondLawRow, springNPerM) + k * sizeof(double));
        turnNmPerRad[k] = field(offsetof(BondLawRow, turnNmPerRad) + k * sizeof(double));
    }
    const Batch one(1.0), h(spacingM);
    bond_law::elasticTerms(s.frame, s.displacementM, s.rotationRad, springNPerM, turnNmPerRad, intact, forceOnHighN, momentNm);
    const Batch inverseLength = one / s.lengthM;
    const Batch along[3] = {s.armM[0] * inverseLength, s.armM[1] * inverseLength, s.armM[2] * inverseLength};
    const Batch overlapM = h - s.lengthM;
    const auto closed = intact < one && overlapM > Batch(0.0);
    if (xsimd::any(closed)) {
        const Batch normalNPerM = byAxis(axis, springNPerM[0], springNPerM[1], springNPerM[2]);
        const Batch contactN = ((one - intact) * normalNPerM) * overlapM;
        for (int i = 0; i < 3; ++i) forceOnHighN[i] = xsimd::select(closed, forceOnHighN[i] + contactN * along[i], forceOnHighN[i]);
    }
    const auto opening = s.lengthM > h;
    if (laws.bulkViscosity > 0.0)
        bond_law::subtractDashpot(xsimd::select(opening, intact, one), laws.bulkViscosity, laws.dashpotPerViscosityNSPerM, s.openingRateMS, along, forceOnHighN);
    for (int k = 0; k < 3; ++k) {
        forceOnHighN[k].store_aligned(&out.forceOnHighN[k][lane0]);
        momentNm[k].store_aligned(&out.bendingMomentNm[k][lane0]);
    }
    const Batch softening = xsimd::select(opening, xsimd::sqrt(intact), one);
    xsimd::select(opening, softening * (s.lengthM - h), s.lengthM - h).store_aligned(&out.stretchM[lane0]);
    (softening * h * h / s.lengthM).store_aligned(&out.volumetricAreaPerArmM[lane0]);
}

template <class Arch>
void MeasureBondStrains::operator()(Arch, const BondStrainInputs& in, size_t first, size_t count, BondStrainRun& out) const
{
    using Batch = xsimd::batch<double, Arch>;
    constexpr size_t width = Batch::size;
    static_assert(BondStrainRun::kCapacity % width == 0, "a run holds whole batches");
    for (size_t lane0 = 0; lane0 < count; lane0 += width) {
        const LaneOffsets<width> at(in, first, count, lane0);
        bond_strain::EndState<Batch> a, b;
        gatherTriples<Arch>(in.positionM, at.low3, a.position), gatherTriples<Arch>(in.positionM, at.high3, b.position);
        gatherTriples<Arch>(in.velocityMS, at.low3, a.velocity), gatherTriples<Arch>(in.velocityMS, at.high3, b.velocity);
        gatherQuads<Arch>(in.quaternion, at.low4, a.quaternion), gatherQuads<Arch>(in.quaternion, at.high4, b.quaternion);
        bond_strain::Strain<Batch> s;
        typename Batch::batch_bool_type small;
        bond_strain::halfwayStrain(a, b, Batch::load_aligned(at.axis), in.spacingM, s, small);
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
        if (!in.laws) continue;
        const LaneRows<Arch> rows(*in.laws, at);
        const SteadyBonds<Batch> bonds = steadyBonds<Arch>(*in.laws, at, rows, s, in.spacingM);
        const auto steady = small && bonds.steady;
        xsimd::select(steady, Batch(1.0), Batch(0.0)).store_aligned(&out.steady[lane0]);
        if (xsimd::any(steady)) storeSteadyTerms<Arch>(*in.laws, rows, Batch::load_aligned(at.axis), bonds.intact, s, in.spacingM, lane0, out);
    }
}

}  // namespace spall
