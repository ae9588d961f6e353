// The bond pass measures bonds in batches as wide as the machine's vector registers (issue 49):
// whichever instruction set does it, each bond's strain must be the one the single-bond formula
// gives, bit for bit, so a run's results do not depend on the machine it runs on; and the bonds
// the batches take must end each step as the one-bond path would leave them.
#include "TestUtil.h"
#include "lattice/BondStrainBatch.h"
#include "lattice/BondStrainKernel.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>

#include <gtest/gtest.h>

#include <array>
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
            bondWords.insert(bondWords.end(), {low, high, uint32_t(b % 3), uint32_t(b % 5 < 3 ? 1 : 0)});  // strength classes 1 and 0
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

/// What the bond laws read besides the strains, for RandomBonds: two strength classes whose
/// rows differ, histories some of them undamaged and some not, random volumetric shares.
struct RandomLaws {
    std::array<BondLawRow, 6> rows{};
    std::vector<double> history, sharesPa, lambdaTracesPa;
    BondLawInputs inputs;

    RandomLaws(size_t particles, size_t bonds)
    {
        std::mt19937 random(11);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        for (size_t r = 0; r < rows.size(); ++r) {
            BondLawRow& row = rows[r];
            const double scale = 1.0 + 0.1 * double(r);
            for (int i = 0; i < 3; ++i) row.springNPerM[i] = scale * 1e8 * (i == int(r % 3) ? 2.0 : 1.0), row.turnNmPerRad[i] = scale * 1e3;
            // Scaled to RandomBonds' strains (a few hundredths of a metre), so that some bonds
            // stay below their largest stretch and shortening so far, and some pass them.
            row.peakStretchM = 0.2 * scale, row.tensionIndexPerM = 1.0 / row.peakStretchM, row.shearIndexPerM = 20.0;
            row.normalIndexPerM = 40.0, row.indexPerPa = 1e-7, row.frictionCoefficient = 0.6;
            row.compressiveStrengthPa = r < 3 ? 3e10 : 0.0, row.crushingPeakShorteningM = 0.05, row.normalModulusPa = 2e10;
            // Softening to three times the peak, but one row snaps at its peak.
            row.zeroTractionStretchM = r == 4 ? row.peakStretchM : 3.0 * row.peakStretchM;
            row.batches = r == 5 ? 0.0 : 1.0;
        }
        for (size_t b = 0; b < bonds; ++b) {
            const double maxStretchM = b % 4 == 0 ? 0.0 : 0.3 * unit(random);
            history.insert(history.end(), {1.0, maxStretchM, 1.0, maxStretchM, 0.0, b % 6 == 0 ? 0.1 * unit(random) : 0.0});
        }
        for (size_t p = 0; p < 3 * particles; ++p) sharesPa.push_back(1e6 * (unit(random) - 0.5));
        for (size_t p = 0; p < particles; ++p) lambdaTracesPa.push_back(-1e7 * unit(random));
        inputs = {rows.data(), history.data(), sharesPa.data(), lambdaTracesPa.data(), 0.06, 1e3};
    }
};

/// Every word of a run's results for lanes below count (their terms only where steady).
std::vector<double> steadyResults(const BondStrainRun& run, size_t count)
{
    std::vector<double> out;
    for (size_t lane = 0; lane < count; ++lane) {
        out.push_back(run.steady[lane]);
        if (run.steady[lane] == 0.0) continue;
        for (int k = 0; k < 3; ++k) out.insert(out.end(), {run.forceOnHighN[k][lane], run.bendingMomentNm[k][lane]});
        out.insert(out.end(), {run.stretchM[lane], run.volumetricAreaPerArmM[lane]});
    }
    return out;
}

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

TEST(LatticeBatches, EveryInstructionSetFindsTheSameElasticBondsAndTerms)
{
    // The narrower sets must find what the widest finds, bit for bit (which, in a lattice, is
    // what the one-bond path finds: BondsMeasuredAsElastic… below).
    const RandomBonds lattice(500, 1000);
    const RandomLaws laws(500, 1000);
    BondStrainInputs inputs = lattice.inputs();
    inputs.laws = &laws.inputs;
    std::vector<double> first;
    size_t steady = 0, measured = 0;
    for (const BondStrainInstructions set : {BondStrainInstructions::Sse2, BondStrainInstructions::Avx2, BondStrainInstructions::Avx512}) {
        if (!machineRuns(set)) continue;
        std::vector<double> results;
        for (size_t begin = 0; begin < 1000; begin += BondStrainRun::kCapacity) {
            const size_t count = std::min(BondStrainRun::kCapacity, 1000 - begin);
            BondStrainRun run;
            measureBondStrainsWith(set, inputs, begin, count, run);
            const std::vector<double> part = steadyResults(run, count);
            results.insert(results.end(), part.begin(), part.end());
            for (size_t lane = 0; lane < count && first.empty(); ++lane) steady += run.steady[lane] != 0.0, ++measured;
        }
        if (first.empty()) {
            first = results;
            continue;
        }
        ASSERT_EQ(results.size(), first.size()) << "instruction set " << int(set) << " finds other bonds steady";
        EXPECT_EQ(std::memcmp(results.data(), first.data(), results.size() * sizeof(double)), 0) << "instruction set " << int(set);
    }
    // Some steady, some not, so the test sees both sides of every condition it can.
    EXPECT_GT(steady, measured / 10);
    EXPECT_LT(steady, measured * 9 / 10);
    std::printf("%zu of %zu bonds steady, the same in every instruction set\n", steady, measured);
}

namespace {

/// Every particle's and bond's state after `steps` steps of a 12³ block at 1 cm on the ground,
/// its particles given random velocities of `speedMS` (each component's standard deviation),
/// gravity acting; as flat bytes, with how many bonds broke.
struct SteppedState {
    std::vector<unsigned char> bytes;
    size_t bonds = 0, broken = 0, damaged = 0, crushed = 0;
    size_t batchedInLastPass = 0;  ///< of the bonds, by the batches
};

template <typename T>
void appendBytes(std::vector<unsigned char>& bytes, const T& value)
{
    const auto* first = reinterpret_cast<const unsigned char*>(&value);
    bytes.insert(bytes.end(), first, first + sizeof value);
}

SteppedState stepBlock(const Material& material, double speedMS, bool batchSteadyBonds, int steps)
{
    const Body block = test::boxBody(12, 12, 12, 0.01, material.densityKgM3, Eigen::Vector3d(0.0, 0.0, 0.06));
    Lattice lattice = Lattice::fromBody(block, material, test::groundAtZero());
    lattice.batchSteadyBonds(batchSteadyBonds);
    std::mt19937 random(3);
    std::normal_distribution<double> velocity(0.0, speedMS);
    for (Eigen::Vector3d& v : lattice.state.velocityMS) v = Eigen::Vector3d(velocity(random), velocity(random), velocity(random));
    lattice.refreshForces();
    const double weightN = -9.81 * lattice.model().particleMassKg;
    lattice.externalForceN.assign(lattice.particleCount(), Eigen::Vector3d(0.0, 0.0, weightN));
    for (int i = 0; i < steps; ++i) lattice.step(lattice.stableTimeStepS());
    SteppedState out;
    out.batchedInLastPass = lattice.bondsBatchedInLastPass();
    out.bonds = lattice.bondCount();
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        appendBytes(out.bytes, lattice.state.positionM[p]), appendBytes(out.bytes, lattice.state.velocityMS[p]);
        appendBytes(out.bytes, lattice.state.angularVelocityRadS[p]), appendBytes(out.bytes, lattice.state.orientation[p].coeffs());
        appendBytes(out.bytes, lattice.state.bondForceN[p]), appendBytes(out.bytes, lattice.state.bondMomentNm[p]);
    }
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        appendBytes(out.bytes, lattice.state.bondHistory[b]);
        out.broken += lattice.bondDamage(b) >= 1.0;
        out.damaged += lattice.bondDamage(b) > 0.0;
        out.crushed += lattice.crushingDamage(b) > 0.0;
    }
    return out;
}

}  // namespace

TEST(LatticeBatches, BondsBatchedEndEachStepAsTheOneBondPathLeavesThem)
{
    // Concrete crushes; masonry has two strength classes; wood's shear is not isotropic, so
    // its bonds along the grain take the one-bond path; glass snaps at its peak. Slow, the
    // bonds stay elastic; fast, they crack and crush, and the batches must hand each bond to
    // the one-bond path the step its damage would start to grow, and take it back, on its
    // secant line and with its crack's contact, once its damage stays.
    size_t broken = 0, crushed = 0;
    for (const char* name : {"concrete", "brick-masonry", "wood", "glass"})
        for (const double speedMS : {0.05, 2.0}) {
            const Material& material = findMaterialPreset(name);
            const SteppedState batched = stepBlock(material, speedMS, true, 150), oneByOne = stepBlock(material, speedMS, false, 150);
            ASSERT_EQ(batched.bytes.size(), oneByOne.bytes.size());
            EXPECT_TRUE(batched.bytes == oneByOne.bytes) << name << " at " << speedMS << " m/s: the batched step differs from the one-bond path";
            // Slowly, bonds stay elastic and the batches take them; fast, most bonds are
            // damaged, and the batches take those whose damage stays: more than the undamaged.
            if (speedMS < 1.0) {
                EXPECT_GT(batched.batchedInLastPass, 0u) << name << ": the batches were meant to take bonds";
            } else if (std::strcmp(name, "concrete") == 0) {
                ASSERT_GT(batched.damaged, batched.bonds / 2) << "fast, concrete's bonds were meant to crack";
                EXPECT_GT(batched.batchedInLastPass, batched.bonds - batched.damaged) << name << ": the batches were meant to take damaged bonds";
            }
            EXPECT_EQ(oneByOne.batchedInLastPass, 0u);
            std::printf("%-14s %4.2f m/s: %5zu bonds damaged, %5zu broken, %5zu crushed, %5zu batched in the last pass; the same bit for bit\n",
                        name, speedMS, batched.damaged, batched.broken, batched.crushed, batched.batchedInLastPass);
            broken += batched.broken, crushed += batched.crushed;
        }
    EXPECT_GT(broken, 0u) << "some bonds were meant to break";
    EXPECT_GT(crushed, 0u) << "some bonds were meant to crush";
}
