// The bond pass measures bonds in batches as wide as the machine's vector registers (issue 49):
// whichever instruction set does it, each bond's strain must be the one the single-bond formula
// gives, bit for bit, so a run's results do not depend on the machine it runs on.
#include "lattice/BondStrainBatch.h"
#include "lattice/BondStrainKernel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

using namespace spall;

namespace {

/// Particles near a cubic lattice's sites, moving and turned by small angles (a few by large ones,
/// which the series cannot take; a few not at all, or about an axis, so that components are zeros
/// of either sign), and bonds between random pairs along each axis.
struct RandomBonds {
    std::vector<double> positionM, velocityMS, quaternion;
    std::vector<uint32_t> bondWords;
    static constexpr double kSpacingM = 0.01;

    RandomBonds(size_t particles, size_t bonds)
    {
        std::mt19937 random(7);
        std::normal_distribution<double> normal(0.0, 1.0);
        std::uniform_int_distribution<uint32_t> pick(0, uint32_t(particles - 1));
        for (size_t p = 0; p < particles; ++p) {
            for (int k = 0; k < 3; ++k) positionM.push_back(kSpacingM * (double(p % 7) + 1e-2 * normal(random)));
            for (int k = 0; k < 3; ++k) velocityMS.push_back(normal(random));
            // Some unturned (the identity, whose zeros carry a sign), some about a lattice axis.
            const double angleRad = p % 10 == 0 ? 0.5 : p % 7 == 0 ? 0.0 : 1e-3 * std::abs(normal(random));
            double axis[3] = {normal(random), normal(random), normal(random)};
            if (p % 5 == 0) axis[0] = axis[1] = 0.0;
            const double norm = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
            // Either sign: q and −q are the same orientation.
            const double sign = p % 3 == 0 ? -1.0 : 1.0;
            for (int k = 0; k < 3; ++k) quaternion.push_back(sign * std::sin(0.5 * angleRad) * axis[k] / norm);
            quaternion.push_back(sign * std::cos(0.5 * angleRad));
        }
        for (size_t b = 0; b < bonds; ++b) {
            const uint32_t low = pick(random), high = pick(random);
            bondWords.insert(bondWords.end(), {low, high, uint32_t(b % 3), 0u});
        }
    }

    BondStrainInputs inputs() const { return {positionM.data(), velocityMS.data(), quaternion.data(), bondWords.data(), kSpacingM}; }

    bond_strain::EndState<double> end(uint32_t p) const
    {
        bond_strain::EndState<double> e;
        for (int k = 0; k < 3; ++k) e.position[k] = positionM[3 * p + k], e.velocity[k] = velocityMS[3 * p + k];
        for (int k = 0; k < 4; ++k) e.quaternion[k] = quaternion[4 * p + k];
        return e;
    }
};

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST(LatticeBatches, EveryInstructionSetMeasuresEachBondAsTheSingleBondFormulaDoes)
{
    const RandomBonds lattice(500, 1000);
    const BondStrainInputs inputs = lattice.inputs();
    int setsRun = 0, largeTurns = 0;
    for (const BondStrainInstructions set : {BondStrainInstructions::Sse2, BondStrainInstructions::Avx2, BondStrainInstructions::Avx512}) {
        if (!machineRuns(set)) continue;
        ++setsRun;
        // Runs of every length up to a full one, so batches end part-way.
        for (size_t first = 0, count = 1; first < 1000; first += count, count = count % BondStrainRun::kCapacity + 1) {
            count = std::min(count, 1000 - first);
            BondStrainRun run;
            measureBondStrainsWith(set, inputs, first, count, run);
            for (size_t lane = 0; lane < count; ++lane) {
                const uint32_t* words = &lattice.bondWords[4 * (first + lane)];
                bond_strain::Strain<double> one;
                bool smallTurn = false;
                bond_strain::halfwayStrain(lattice.end(words[0]), lattice.end(words[1]), int(words[2]), RandomBonds::kSpacingM, one, smallTurn);
                ASSERT_EQ(run.smallTurn[lane] != 0.0, smallTurn) << "bond " << first + lane;
                largeTurns += !smallTurn;
                if (!smallTurn) continue;  // measured alone by the bond pass
                bool same = sameBits(run.lengthM[lane], one.lengthM) && sameBits(run.openingRateMS[lane], one.openingRateMS);
                for (int r = 0; r < 3; ++r) {
                    for (int c = 0; c < 3; ++c) same = same && sameBits(run.frame[r][c][lane], one.frame[r][c]);
                    same = same && sameBits(run.displacementM[r][lane], one.displacementM[r]) && sameBits(run.rotationRad[r][lane], one.rotationRad[r]) &&
                           sameBits(run.armM[r][lane], one.armM[r]);
                }
                ASSERT_TRUE(same) << "instruction set " << int(set) << ", bond " << first + lane;
            }
        }
    }
    EXPECT_GE(setsRun, 1) << "every x86-64 runs SSE2";
    EXPECT_GT(largeTurns, 0) << "the large turns were meant to be tried";
    std::printf("%d instruction sets agree with the single-bond formula bit for bit\n", setsRun);
}
