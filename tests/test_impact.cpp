// Impact fracture (issue 48 item 2): a rigid body that strikes the ground faster than its
// material may take without cracking becomes a lattice for the impact, which decides what breaks.
#include "LatticeTestUtil.h"

#include <spall/lattice/Deformable.h>
#include <spall/scene/Scene.h>
#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

using namespace spall;

namespace {

constexpr double kG = 9.81;

/// A 0.6 × 0.6 × 0.1 m slab of the concrete preset in 2.5 cm voxels, turned `tiltDeg` about y,
/// dropped from rest with its lowest point `heightM` above the ground, followed until `afterS`
/// after it lands.
struct Drop {
    size_t bodies = 0;
    int64_t brokenBonds = 0;
    size_t impactEntries = 0;  ///< hand-offs: each impact entry leaves once
    int64_t latticeParticleSteps = 0;
};
Drop dropSlab(double heightM, double tiltDeg, double afterS = 0.05, bool impactFracture = true)
{
    const double liftM = 0.05 * std::cos(tiltDeg * M_PI / 180) + 0.3 * std::sin(tiltDeg * M_PI / 180);
    const nlohmann::json scene = {
        {"voxel_size_m", 0.025},
        {"frame_rate_hz", 100},
        {"objects",
         {{{"primitive", {{"shape", "box"}, {"size_m", {0.6, 0.6, 0.1}}}},
           {"position_m", {0, 0, heightM + liftM}},
           {"rotation_deg", {0, tiltDeg, 0}},
           {"material", "concrete"}}}},
        {"fracture", {{"algorithm", "lattice"}}},
        {"lattice", {{"impact_fracture", impactFracture}}},
    };
    Simulation sim(parseScene(scene.dump(), "drop", "."));
    sim.advanceTo(std::sqrt(2 * heightM / kG) + afterS);
    Drop drop{sim.bodies().size(), 0, sim.state().handOffs.size(), sim.state().stepStats.latticeParticleSteps};
    for (const HandOffRecord& h : sim.state().handOffs) drop.brokenBonds += h.brokenBonds;
    return drop;
}

}  // namespace

TEST(Impact, ASlabDroppedFlatBreaksFrom3MetresAndNotFrom5Centimetres)
{
    // Concrete (ρ c = 9.47 MPa s/m): from 5 cm (0.99 m/s) the face that strikes takes 9.4 MPa,
    // a quarter of fcm, and nothing breaks; from 3 m (7.7 m/s) it takes 72.6 MPa, twice fcm, and
    // the slab comes apart. The gentle drop's rebounds strike slower than the impact it
    // survived, so it enters the phase once.
    const Drop gentle = dropSlab(0.05, 0.0), high = dropSlab(3.0, 0.0);
    for (const auto& [name, d] : {std::pair{"5 cm", gentle}, {"3 m", high}})
        std::printf("%-4s: %zu bodies, %lld bonds broken, %zu impact entries, %.1f M particle-steps\n", name, d.bodies, (long long)d.brokenBonds,
                    d.impactEntries, d.latticeParticleSteps / 1e6);
    EXPECT_EQ(gentle.bodies, 1u);
    EXPECT_EQ(gentle.brokenBonds, 0);
    EXPECT_EQ(gentle.impactEntries, 1u);
    EXPECT_GE(high.bodies, 2u);
}

TEST(Impact, HigherDropsBreakASlabIntoMorePieces)
{
    // 3° off flat, so one edge strikes first and the slab slaps down after it.
    const Drop low = dropSlab(0.5, 3.0), high = dropSlab(3.0, 3.0);
    std::printf("tilted 3 degrees: from 0.5 m %zu bodies, from 3 m %zu\n", low.bodies, high.bodies);
    EXPECT_GE(low.bodies, 2u);
    EXPECT_GT(high.bodies, 2 * low.bodies);
}

TEST(Impact, NothingEntersBelowTheCrackingSpeedOrWhenSwitchedOff)
{
    // The slab's cracking speed is ft / (8 ρ c) = 0.038 m/s, a drop of 0.075 mm: from 0.05 mm
    // and from 3 m without impact fracture it stays a rigid body.
    const Material concrete = findMaterialPreset("concrete");
    EXPECT_NEAR(crackingImpactSpeedMS(concrete), 0.125 * 2.9e6 / (2400 * 3944), 1e-4);
    const Drop below = dropSlab(5e-5, 0.0, 0.02), off = dropSlab(3.0, 0.0, 0.02, false);
    EXPECT_EQ(below.latticeParticleSteps, 0);
    EXPECT_EQ(off.latticeParticleSteps, 0);
    EXPECT_EQ(off.bodies, 1u);
}

TEST(Impact, TheCrackingSpeedDamagesNoBondOfASlabThatStrikesEdgeFirst)
{
    // The gate's margin: the slab, 3° off flat, striking the ground as a lattice at the cracking
    // speed takes no damage at all, though at twice it, ft / (4 ρ c), its edge is damaged.
    const Material concrete = findMaterialPreset("concrete");
    const auto worstDamage = [&](double speedMS) {
        const double tilt = 3.0 * M_PI / 180;
        Body slab = test::boxBody(24, 24, 4, 0.025, concrete.densityKgM3, Eigen::Vector3d(0, 0, 0.05 + 0.3 * std::sin(tilt) + 0.001));
        slab.motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitY()));
        slab.motion.linearVelocityMS = Eigen::Vector3d(0, 0, -speedMS);
        Lattice lattice = enterDeformablePhase(slab, concrete, LatticeSettings(), test::groundAtZero(), 1, 0.0).lattice;
        for (Eigen::Vector3d& f : lattice.externalForceN) f = Eigen::Vector3d(0, 0, -kG * lattice.model().particleMassKg);
        const double dt = lattice.stableTimeStepS();
        double worst = 0.0;
        for (double t = 0; t < 0.02; t += dt) lattice.step(dt);
        for (size_t b = 0; b < lattice.bondCount(); ++b) worst = std::max(worst, lattice.bondDamage(b));
        return worst;
    };
    const double gateMS = crackingImpactSpeedMS(concrete), atGate = worstDamage(gateMS), atTwice = worstDamage(2 * gateMS);
    std::printf("worst bond damage: %.3f at %.3f m/s, %.3f at twice it\n", atGate, gateMS, atTwice);
    EXPECT_EQ(atGate, 0.0);
    EXPECT_GT(atTwice, 0.0) << "the margin is a factor of 2, not more";
}
