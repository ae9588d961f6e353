// Issue 47, item 8: a homogeneous material's fragments must not depend on the voxel size once it
// is fine enough. A plain concrete wall panel at h and h/2 over five standoffs: the count of pieces
// above a fixed mass and the mass-weighted median mass, within 25 % between the two.
//
// One seed's pieces scatter by more than 25 % at a single voxel size near a breaking threshold, so
// each size is the mean over three seeds of the concrete's strength field. Disabled: it takes
// about 20 minutes, and the lattice is not known to meet it (docs/accuracy.md, "Fragments against
// the voxel size"). Run it with
//   build/spall_tests --gtest_also_run_disabled_tests --gtest_filter='FragmentConvergence.*'
#include "LatticeTestUtil.h"
#include "PulseResponse.h"
#include "TestUtil.h"

#include <spall/lattice/Lattice.h>
#include <spall/scene/Scene.h>
#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

using namespace spall;

namespace {

struct PanelFragments {
    double piecesAboveFixedMass = 0.0;
    double massWeightedMedianKg = 0.0;
};

/// A plain concrete panel 0.5 × 0.1 × 0.5 m standing on the ground, anchored to it, 1.5 kg of TNT
/// at its middle `standoffM` from its front face, voxels of h; the bodies after 30 ms.
/// Figures are doubles so that seeds can be averaged.
PanelFragments panelFragments(double h, double standoffM, double fixedMassKg, int seed)
{
    const double thicknessM = 0.1, sideM = 0.5;
    const nlohmann::json j = {
        {"voxel_size_m", h}, {"duration_s", 0.03}, {"frame_rate_hz", 100}, {"seed", seed},
        {"objects", {{{"name", "panel"}, {"primitive", {{"shape", "box"}, {"size_m", {sideM, thicknessM, sideM}}}}, {"position_m", {0.0, 0.0, 0.5 * sideM}},
                      {"material", "concrete"}, {"anchor", "ground"}}}},
        {"charges", {{{"position_m", {0.0, -standoffM - 0.5 * thicknessM, 0.5 * sideM}}, {"tnt_kg", 1.5}, {"burst", "free-air"}}}},
        {"fracture", {{"algorithm", "lattice"}}},
    };
    Simulation sim(parseScene(j.dump(), "panel", "."));
    sim.advanceTo(0.03);
    std::vector<double> masses;
    for (const Body& body : sim.bodies()) masses.push_back(body.mass.massKg);
    std::sort(masses.begin(), masses.end());
    PanelFragments result;
    result.piecesAboveFixedMass = double(std::count_if(masses.begin(), masses.end(), [&](double m) { return m >= fixedMassKg; }));
    const double totalKg = std::accumulate(masses.begin(), masses.end(), 0.0);
    double below = 0.0;
    for (const double m : masses)
        if ((below += m) >= 0.5 * totalKg) {
            result.massWeightedMedianKg = m;
            break;
        }
    std::printf("h %.4f m, standoff %.2f m, seed %d: %zu bodies, %.0f of %.2f kg or more, mass-weighted median %.2f kg\n", h, standoffM, seed, masses.size(),
                result.piecesAboveFixedMass, fixedMassKg, result.massWeightedMedianKg);
    return result;
}

/// The mean over seeds 1 to 3.
PanelFragments meanOverSeeds(double h, double standoffM, double fixedMassKg)
{
    PanelFragments mean;
    const int seeds = 3;
    for (int seed = 1; seed <= seeds; ++seed) {
        const PanelFragments one = panelFragments(h, standoffM, fixedMassKg, seed);
        mean.piecesAboveFixedMass += one.piecesAboveFixedMass / seeds;
        mean.massWeightedMedianKg += one.massWeightedMedianKg / seeds;
    }
    return mean;
}

/// A plain concrete strip 0.5 m tall, 0.1 m thick and 5 cm wide, its base bonded to the
/// ground, voxels of h (strength scatter and rate law off, so both sizes hold the same
/// material), under a uniform pulse on its front face: impulsePaS over 0.3 ms, falling
/// linearly, no gravity. Its top's mean deflection (unit: m) and broken bonds after 15 ms.
struct StripSwing {
    double topDeflectionM = 0.0;
    size_t brokenBonds = 0;
};
StripSwing stripSwing(double h, double impulsePaS)
{
    Material concrete = test::withoutStrengthScatter(findMaterialPreset("concrete"));
    concrete.strengthRateLaw = StrengthRateLaw::None;
    const double widthM = 0.05, thicknessM = 0.1, heightM = 0.5, pulseS = 3e-4, runS = 0.015;
    const int nz = int(std::lround(heightM / h));
    Body body = test::boxBody(int(std::lround(widthM / h)), int(std::lround(thicknessM / h)), nz, h, concrete.densityKgM3);
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (it.getCoord().z() == 0) it.setValue(*it | kAnchorBit);
    refreshDerivedData(body);
    body.motion.positionM = Eigen::Vector3d(0.0, 0.0, 0.5 * heightM);
    Lattice lattice = Lattice::fromBody(body, concrete, test::groundAtZero());
    std::vector<size_t> front, top;
    for (size_t p = 0; p < lattice.model().voxelParticleCount; ++p) {
        if (lattice.model().voxel[p].y() == 0) front.push_back(p);
        if (lattice.model().voxel[p].z() == nz - 1) top.push_back(p);
    }
    double topAtRestM = 0.0;
    for (const size_t p : top) topAtRestM += lattice.state.positionM[p].y() / double(top.size());
    // The pulse, then free motion for the rest of the run.
    test::stepUnderTriangularPulse(lattice, front, Eigen::Vector3d::UnitY(), 2.0 * impulsePaS / pulseS, pulseS, runS);
    StripSwing swing;
    for (const size_t p : top) swing.topDeflectionM += lattice.state.positionM[p].y() / double(top.size());
    swing.topDeflectionM -= topAtRestM;
    for (size_t b = 0; b < lattice.bondCount(); ++b) swing.brokenBonds += lattice.bondDamage(b) >= 1.0;
    std::printf("h %.4f m, %.0f Pa s: the top %.3f mm off after %.0f ms, %zu bonds broken\n", h, impulsePaS, 1e3 * swing.topDeflectionM, 1e3 * runS,
                swing.brokenBonds);
    return swing;
}
}  // namespace

TEST(FragmentConvergence, AStripKnockedOffItsBaseByAShortPulseSwingsAlikeAtTwoVoxelSizes)
{
    // What the panel's pieces rest on: the lattice's answer to a short pulse, once its base
    // cracks through, must not depend on the voxel size. 150 Pa s breaks the base at both sizes;
    // freed at once, the strip would turn about its base's rear edge with the pulse's moment
    // about it, 150 Pa s × b L² / 2, over m (L² + t²) / 3: its top at 0.90 m/s, 13.5 mm in
    // 15 ms. The base's cracking takes part of that, so the lattice's swing must lie below it.
    const double rigidRockingBoundM = 0.0135;
    const StripSwing coarse = stripSwing(0.025, 150.0), fine = stripSwing(0.0125, 150.0);
    EXPECT_GT(coarse.brokenBonds, 0u);
    EXPECT_GT(fine.brokenBonds, 0u);
    EXPECT_NEAR(fine.topDeflectionM / coarse.topDeflectionM, 1.0, 0.25);
    EXPECT_LT(std::max(coarse.topDeflectionM, fine.topDeflectionM), rigidRockingBoundM);
    // 60 Pa s leaves it standing at both: cracked near its base, nothing broken, its top back
    // within a millimetre of where it stood.
    for (const double h : {0.025, 0.0125}) {
        const StripSwing weak = stripSwing(h, 60.0);
        EXPECT_EQ(weak.brokenBonds, 0u) << "h " << h;
        EXPECT_LT(std::abs(weak.topDeflectionM), 1e-3) << "h " << h;
    }
}

TEST(FragmentConvergence, DISABLED_AConcretePanelsFragmentsAgreeAtTheTwoFinestVoxelSizes)
{
    // 2.5 cm puts four particles through the panel's thickness; the fixed mass is 16 of them.
    const double h = 0.025, fixedMassKg = 0.4;
    for (const double standoffM : {0.10, 0.15, 0.20, 0.30, 0.40}) {
        const PanelFragments coarse = meanOverSeeds(h, standoffM, fixedMassKg), fine = meanOverSeeds(0.5 * h, standoffM, fixedMassKg);
        std::printf("standoff %.2f m: pieces of %.2f kg or more %.1f at h, %.1f at h/2; mass-weighted median %.2f and %.2f kg\n", standoffM,
                    fixedMassKg, coarse.piecesAboveFixedMass, fine.piecesAboveFixedMass, coarse.massWeightedMedianKg, fine.massWeightedMedianKg);
        const auto within25Percent = [](double a, double b) { return std::abs(a - b) <= 0.25 * std::max(a, b); };
        EXPECT_TRUE(within25Percent(coarse.piecesAboveFixedMass, fine.piecesAboveFixedMass)) << "standoff " << standoffM << " m";
        EXPECT_TRUE(within25Percent(coarse.massWeightedMedianKg, fine.massWeightedMedianKg)) << "standoff " << standoffM << " m";
    }
}

