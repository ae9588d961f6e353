// The deformable phase around its lattice: the rigid fit against a rigid motion (which it must
// reproduce exactly), the hand-off against conservation of each piece's momentum, and whole
// simulations against what a wall must do (stand a small charge, break under a large one).
#include "LatticeTestUtil.h"

#include <spall/blast/Blast.h>
#include <spall/dynamics/Integrate.h>
#include <spall/scene/Scene.h>
#include <spall/lattice/Deformable.h>
#include <spall/sim/Checkpoint.h>
#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <map>
#include <numeric>
#include <random>

using namespace spall;
using test::allParticles;
using test::momentaOf;

namespace {

constexpr double kH = 0.05;

}  // namespace

TEST(Deformable, RigidFitReproducesARigidMotionExactly)
{
    const Eigen::Quaterniond turned(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, -1).normalized()));
    Body body = test::boxBody(5, 3, 2, kH, 1900.0, Eigen::Vector3d(1, -2, 0.5), turned);
    body.motion.linearVelocityMS = Eigen::Vector3d(3, -1, 2);
    body.motion.angularVelocityRadS = Eigen::Vector3d(0.5, 4, -2);
    const Lattice lattice = Lattice::fromBody(body, findMaterialPreset("brick-masonry"));
    const RigidFit fit = fitRigidMotion(lattice, allParticles(lattice));
    EXPECT_LT((fit.centreM - body.motion.positionM).norm(), 1e-12);
    EXPECT_LT((fit.rotation - turned.toRotationMatrix()).norm(), 1e-12);
    EXPECT_LT((fit.velocityMS - body.motion.linearVelocityMS).norm(), 1e-12);
    const Eigen::Vector3d spin = body.worldInertiaKgM2() * body.motion.angularVelocityRadS;
    EXPECT_LT((fit.angularMomentumKgM2S - spin).norm(), 1e-12 * spin.norm());
    // Following the lattice gives the body its motion back; a rigid lattice vibrates not at all.
    Body follower = body;
    follower.motion = BodyMotion();
    followLattice(follower, lattice);
    EXPECT_LT((follower.motion.angularVelocityRadS - body.motion.angularVelocityRadS).norm(), 1e-10);
    EXPECT_LT(vibrationEnergyJ(lattice), 1e-10 * kineticEnergyJ(body));
}

TEST(Deformable, HandOffKeepsEveryPiecesMomentumAndBreaksTheLinksThatBroke)
{
    Body bar = test::boxBody(8, 2, 2, kH, 1900.0, Eigen::Vector3d(0.3, 0.2, 1.0));
    Lattice lattice = Lattice::fromBody(bar, findMaterialPreset("brick-masonry"));
    std::mt19937 random(7);
    std::normal_distribution<double> normal(0.0, 1.0);
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        lattice.state.velocityMS[p] += Eigen::Vector3d(normal(random), normal(random), normal(random));
        lattice.state.angularVelocityRadS[p] = 10.0 * Eigen::Vector3d(normal(random), normal(random), normal(random));
        lattice.state.positionM[p] += 1e-7 * Eigen::Vector3d(normal(random), normal(random), normal(random));
    }
    // The four bonds between x = 3 and x = 4 have broken.
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (lattice.model().bonds[b].axis == 0 && lattice.model().voxel[lattice.model().bonds[b].low].x() == 3) lattice.state.bondHistory[b].maxEquivalentStretchM = 1.0;
    lattice.refreshForces();
    const HandOff handed = handOff(bar, lattice);
    ASSERT_EQ(handed.parts.size(), 2u);
    EXPECT_EQ(handed.brokenBonds, 4);
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    for (const Body& part : handed.parts) {
        // Each part carries exactly its own particles' momenta.
        std::vector<uint32_t> mine;
        for (uint32_t p = 0; p < lattice.particleCount(); ++p)
            if (part.grid->tree().isValueOn(lattice.model().voxel[p])) mine.push_back(p);
        const auto [ownLinear, ownAngular] = momentaOf(lattice, mine);
        EXPECT_LT((linearMomentum(part) - ownLinear).norm(), 1e-12 * ownLinear.norm());
        EXPECT_LT((angularMomentumAboutOrigin(part) - ownAngular).norm(), 1e-12 * ownAngular.norm());
        linear += linearMomentum(part);
        angular += angularMomentumAboutOrigin(part);
        // The broken face is fracture surface in the frames.
        int brokenFaces = 0;
        for (auto it = part.grid->cbeginValueOn(); it; ++it) brokenFaces += brokenFaceBits(*it) != 0;
        EXPECT_EQ(brokenFaces, 4);
    }
    EXPECT_LT((linear - lattice.linearMomentum()).norm(), 1e-12 * lattice.linearMomentum().norm());
    EXPECT_LT((angular - lattice.angularMomentumAboutOrigin()).norm(), 1e-12 * lattice.angularMomentumAboutOrigin().norm());
    // Rigid motion with the same momenta holds less kinetic energy than any other motion, so
    // what the random motion had beyond it is vibration.
    EXPECT_GT(vibrationEnergyJ(lattice), 0.0);
}

namespace {

/// An unreinforced brick wall 1 m wide, 0.2 m thick, 1 m high standing on (anchored to) the
/// ground, 0.05 m voxels, with a charge of `tntKg` on its axis `standoffM` in front at half
/// height, fracture from stress, the deformable phase cut at 30 ms after the blast (the wall's
/// bending period is about 10 ms).
/// Brick masonry with every bond alike: the walls below check mechanisms at thresholds set by
/// the mean strength (with the preset's scatter each seed moves them; docs/accuracy.md,
/// "Strength scatter").
const nlohmann::json kMeanBrick = {{"mean-brick", {{"base", "brick-masonry"}, {"strength_cov", 0.0}, {"unit_strength_cov", 0.0}}}};

Scene wallScene(double tntKg, double standoffM, const std::vector<double>& detonationTimesS = {0.0})
{
    nlohmann::json charges = nlohmann::json::array();
    for (const double timeS : detonationTimesS)
        charges.push_back({{"position_m", {0, -0.1 - standoffM, 0.5}}, {"tnt_kg", tntKg}, {"burst", "free-air"}, {"detonation_time_s", timeS}});
    nlohmann::json j = {
        {"voxel_size_m", kH}, {"duration_s", 0.1}, {"frame_rate_hz", 24}, {"seed", 1},
        {"objects", {{{"name", "wall"}, {"primitive", {{"shape", "box"}, {"size_m", {1.0, 0.2, 1.0}}}}, {"position_m", {0, 0, 0.5}},
                      {"material", "mean-brick"}, {"anchor", "ground"}}}},
        {"materials", kMeanBrick},
        {"charges", charges},
        {"fracture", {{"algorithm", "lattice"}}},
        {"lattice", {{"max_vibration_s", 0.03}}},
    };
    return parseScene(j.dump(), "wall", ".");
}

/// Bonds broken so far, those to the ground included: the crack surface in voxel faces.
int64_t brokenBondsOf(const Simulation& sim)
{
    int64_t broken = 0;
    for (const HandOffRecord& h : sim.state().handOffs) broken += h.brokenBonds + h.brokenAnchors;
    return broken;
}

}  // namespace

TEST(Deformable, APartHeldByAnotherFaceThanItsWholeStartsThatSupportAtRest)
{
    // Two voxels, A anchored, B beside it inside a static box. The whole's A has no free face
    // into the box (B is there), so A is simply held. A on its own has: its part's lattice holds
    // it by a support point where B was. That point is a held support, not B carrying on, so it
    // starts at rest one voxel beyond A (it once took B's state, and drifted with B's velocity).
    const double h = 0.1;
    Body whole = test::boxBody(2, 1, 1, h, 2000.0, Eigen::Vector3d(1.0, 0, 0.5));
    whole.grid->tree().setValue(openvdb::Coord(0, 0, 0), whole.grid->tree().getValue(openvdb::Coord(0, 0, 0)) | kAnchorBit);
    refreshDerivedData(whole);
    const Eigen::Vector3d a = whole.voxelWorldM(openvdb::Coord(0, 0, 0)), b = whole.voxelWorldM(openvdb::Coord(1, 0, 0));
    StaticWorld supports;
    supports.boxes.push_back({b + Eigen::Vector3d(0.26, 0, 0), Eigen::Vector3d(0.3, 0.3, 0.3), Eigen::Quaterniond::Identity()});
    const Material& material = findMaterialPreset("concrete");
    DeformableBody deforming = enterDeformablePhase(whole, material, LatticeSettings(), supports, 1, 0.0);
    ASSERT_EQ(deforming.lattice.particleCount(), 2u) << "the whole's A is held, with no support point";
    deforming.lattice.state.velocityMS[1] = Eigen::Vector3d(2.0, 0, 0);
    deforming.lattice.state.positionM[1] += Eigen::Vector3d(0.01, 0, 0);

    Body part = whole;
    part.grid = whole.grid->deepCopy();
    auto links = part.grid->getAccessor();
    breakLink(links, openvdb::Coord(0, 0, 0), kPosX);
    links.setValueOff(openvdb::Coord(1, 0, 0), 0);
    refreshDerivedData(part);
    part.motion.positionM = a;
    const DeformableBody continued = continueDeformable(part, deforming, material, LatticeSettings(), supports, 1);
    ASSERT_EQ(continued.lattice.particleCount(), 2u) << "the part's A is held by a support point";
    EXPECT_TRUE(continued.lattice.model().held[1]);
    EXPECT_EQ(continued.lattice.state.velocityMS[1], Eigen::Vector3d::Zero());
    EXPECT_LT((continued.lattice.state.positionM[1] - (a + Eigen::Vector3d(h, 0, 0))).norm(), 1e-12);
}

TEST(Deformable, BrickWallStandsAGramOfTntAt30cm)
{
    // Issue 17: 1 g of TNT 0.3 m from a brick wall (about 80 kPa side-on for 0.3 ms, an impulse
    // that does not crack a real wall) broke 32 links under the pressure rule.
    Simulation sim(wallScene(0.001, 0.3));
    sim.advanceTo(0.05);
    EXPECT_TRUE(sim.state().deformable.empty()) << "the wall is still deformable after 50 ms";
    ASSERT_FALSE(sim.state().handOffs.empty());
    EXPECT_EQ(brokenBondsOf(sim), 0);
    EXPECT_EQ(sim.bodies().size(), 1u);
}

TEST(Deformable, BrickWallBreaksUnderAKilogramAt50cm)
{
    // Broken into pieces, and off its base: the base's bed joint, loaded at once in flexure
    // and in shear, cracks through (the classic failure of an unreinforced cantilever wall,
    // which then rocks on its base). With tension failure only, a stump stayed bonded.
    Simulation sim(wallScene(1.0, 0.5));
    sim.advanceTo(0.05);
    EXPECT_GT(brokenBondsOf(sim), 0);
    EXPECT_GT(sim.bodies().size(), 2u);
}

TEST(Deformable, TheFramesCountAWallsMotionWhileItIsALattice)
{
    // Issue 48: an anchored wall swinging under the blast has a pose that does not move (it is
    // anchored) and a lattice that does; the frames' kinetic energy and momenta are the
    // lattice's. Before, the history said 0 J until the hand-off.
    Simulation sim(wallScene(0.011, 0.5));
    sim.advanceTo(0.003);
    ASSERT_EQ(sim.state().deformable.lattices.size(), 1u) << "the wall is meant to be a lattice at 3 ms";
    const Lattice& lattice = sim.state().deformable.lattices.front().lattice;
    const size_t wall = sim.state().deformable.bodyIndex(0, sim.bodies());
    ASSERT_TRUE(sim.bodies()[wall].anchored);
    ASSERT_TRUE(lattice.heldBySupport()) << "still held by its base, its body does not follow it";
    EXPECT_EQ(kineticEnergyJ(sim.bodies()[wall]), 0.0) << "its rigid pose is anchored";
    const BodyMomenta motion = sim.bodyMomenta()[wall];
    std::printf("at 3 ms the wall's lattice holds %.1f J and %.2f kg m/s\n", motion.kineticEnergyJ, motion.linearMomentumKgMS.norm());
    EXPECT_GT(motion.kineticEnergyJ, 0.1) << "11 g at 0.5 m sets it moving";
    EXPECT_EQ(motion.kineticEnergyJ, lattice.kineticEnergyJ());
    EXPECT_EQ(motion.linearMomentumKgMS, lattice.linearMomentum());
    EXPECT_GT(motion.linearMomentumKgMS.y(), 0.0) << "away from the charge, which is on the wall's -y side";
}

TEST(Deformable, AWallsPiecesShowAsTheySeparateAndKeepTheirIdsThroughTheHandOff)
{
    // Issue 48, item 4: the frames show a lattice's pieces as they come apart, and a piece shown
    // keeps its id and its path when it leaves the phase. Before, the wall stood whole in every
    // frame until the hand-off, when its pieces appeared at once under new ids.
    Simulation sim(wallScene(1.0, 0.5));
    const int64_t wallId = sim.bodies().front().id;
    const int64_t wallVoxels = sim.bodies().front().mass.voxelCount;
    const auto holdsWall = [&] { return std::any_of(sim.bodies().begin(), sim.bodies().end(), [&](const Body& b) { return b.id == wallId; }); };
    const double frameS = 0.0005;
    std::vector<Body> lastShown;
    double lastShownS = 0.0;
    double firstSeparateS = -1.0;
    while (holdsWall() && sim.timeS() < 0.05) {
        std::vector<Body> shown = sim.showPieces();
        if (shown.size() > 1) {
            if (firstSeparateS < 0.0) firstSeparateS = sim.timeS();
            std::map<int64_t, int> timesShown;
            int64_t voxels = 0;
            for (const Body& piece : shown) {
                EXPECT_EQ(++timesShown[piece.id], 1) << "id " << piece.id << " shown twice at " << sim.timeS() << " s";
                EXPECT_EQ(piece.parentId, wallId);
                voxels += piece.mass.voxelCount;
            }
            EXPECT_EQ(voxels, wallVoxels) << "the pieces shown are the wall, all of it, at " << sim.timeS() << " s";
        }
        lastShown = std::move(shown);
        lastShownS = sim.timeS();
        sim.advanceTo(sim.timeS() + frameS);
    }
    ASSERT_FALSE(holdsWall()) << "the wall is meant to leave the phase in pieces within 50 ms";
    std::printf("pieces first shown at %.1f ms, %zu shown at %.1f ms, %zu bodies at the hand-off's frame %.1f ms\n", 1e3 * firstSeparateS,
                lastShown.size(), 1e3 * lastShownS, sim.bodies().size(), 1e3 * sim.timeS());
    ASSERT_GT(firstSeparateS, 0.0);
    EXPECT_LT(firstSeparateS, lastShownS) << "shown in pieces in a frame before the one that hands them off";
    // A piece shown keeps its id when it leaves, where its shown motion takes it to within a voxel.
    std::map<int64_t, const Body*> now;
    for (const Body& b : sim.bodies()) now[b.id] = &b;
    const double dtS = sim.timeS() - lastShownS;
    double shownKg = 0.0, keptKg = 0.0, largestJumpM = 0.0;
    for (const Body& piece : lastShown) {
        shownKg += piece.mass.massKg;
        const auto found = now.find(piece.id);
        if (found == now.end()) continue;
        keptKg += piece.mass.massKg;
        const Eigen::Vector3d expectedM = piece.motion.positionM + dtS * piece.motion.linearVelocityMS;
        largestJumpM = std::max(largestJumpM, (found->second->motion.positionM - expectedM).norm());
    }
    std::printf("%.0f %% of the mass shown keeps its ids; its largest jump beyond its motion %.2f mm\n", 100.0 * keptKg / shownKg, 1e3 * largestJumpM);
    EXPECT_GT(keptKg, 0.9 * shownKg);
    EXPECT_LT(largestJumpM, kH);
}

TEST(Deformable, PiecesShownBeforeACheckpointKeepTheirIdsAfterIt)
{
    // A run resumed from a checkpoint taken while the frames show a wall in pieces names its
    // pieces as the uninterrupted run does: the ids shown go through the checkpoint.
    const Scene scene = wallScene(1.0, 0.5);
    Simulation straight(scene), interrupted(scene);
    for (Simulation* sim : {&straight, &interrupted}) sim->advanceTo(0.002);
    ASSERT_GT(straight.showPieces().size(), straight.bodies().size()) << "the wall is meant to show pieces at 2 ms";
    ASSERT_GT(interrupted.showPieces().size(), interrupted.bodies().size());
    const std::string path = testing::TempDir() + "/spall-test-shown-pieces.checkpoint";
    writeCheckpoint(path, {1, 12, 10, sceneToJson(interrupted.scene()).dump(), interrupted.state(), {}});
    Checkpoint back = readCheckpoint(path);
    Simulation resumed(parseScene(back.sceneJson, "checkpoint", "."), std::move(back.state));
    for (double t = 0.0025; t < 0.03; t += 0.0005) {
        std::vector<Body> a = straight.showPieces(), b = resumed.showPieces();
        ASSERT_EQ(a.size(), b.size()) << "at " << t << " s";
        for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i].id, b[i].id) << "body " << i << " at " << t << " s";
        straight.advanceTo(t);
        resumed.advanceTo(t);
    }
    ASSERT_EQ(straight.bodies().size(), resumed.bodies().size());
    for (size_t i = 0; i < straight.bodies().size(); ++i) EXPECT_EQ(straight.bodies()[i].id, resumed.bodies()[i].id);
}

TEST(Deformable, TheDeformablePhaseTakesNoMoreParticleStepsThanItsBoundSays)
{
    // Issue 50: the progress bar's time to come in the deformable phase is this bound at the
    // pace so far; it must bound what the phase then does.
    Simulation sim(wallScene(1.0, 0.5));
    sim.advanceTo(0.003);
    const Scene& scene = sim.scene();
    ASSERT_FALSE(sim.state().deformable.empty());
    const int64_t bound = sim.state().deformable.particleStepsLeftAtMost(sim.timeS(), scene.lattice.maxVibrationS);
    sim.takeStepStats();
    int64_t taken = 0;
    while (!sim.state().deformable.empty()) {
        sim.advanceTo(sim.timeS() + 0.005);
        taken += sim.takeStepStats().latticeParticleSteps;
    }
    std::printf("at 3 ms: at most %lld particle-steps to come; the phase took %lld\n", static_cast<long long>(bound), static_cast<long long>(taken));
    EXPECT_LE(taken, bound);
    EXPECT_GT(taken, 0);
    EXPECT_EQ(sim.state().deformable.particleStepsLeftAtMost(sim.timeS(), scene.lattice.maxVibrationS), 0) << "nothing left once it is over";
}

TEST(Deformable, TwoChargesInSequenceBreakAWallThatEitherAloneLeavesStanding)
{
    // Issue 47: damage is state. 11 g of TNT 0.5 m from the wall takes its base's bonds far
    // along their softening lines but breaks none; the same charge again 60 ms later, once the
    // wall has left the phase, meets it as the first left it and breaks its base. (Either charge
    // alone is the same run shifted in time. With every bond's history reset on re-entry, as
    // before this, the pair broke nothing from 6 to 12 g. Since a bond left with less than a
    // tenth of its strength counts as broken at hand-off, issue 48, 12 g alone breaks the base.)
    Simulation sim(wallScene(0.011, 0.5, {0.0, 0.06}));
    sim.advanceTo(0.06);
    ASSERT_TRUE(sim.state().deformable.empty()) << "the wall is meant to have left the phase before the second charge";
    ASSERT_EQ(sim.bodies().size(), 1u);
    EXPECT_EQ(brokenBondsOf(sim), 0) << "the first charge alone";
    const Body& wall = sim.bodies().front();
    ASSERT_TRUE(wall.linkDamage) << "the wall remembers no damage";
    float mostAnchorDamage = 0.0f;
    for (auto it = wall.linkDamage->cbeginValueOn(); it; ++it) mostAnchorDamage = std::max(mostAnchorDamage, (*it)[kAnchorDamage]);
    EXPECT_GT(mostAnchorDamage, 0.85f);
    sim.advanceTo(0.12);
    std::printf("after the first charge: the most damaged anchor at %.3f; after both, %lld bonds broken\n", double(mostAnchorDamage),
                static_cast<long long>(brokenBondsOf(sim)));
    EXPECT_GT(brokenBondsOf(sim), 0) << "the second charge";
}

TEST(Deformable, ALatticeStepsOnItsOwnClockAtItsStableStep)
{
    // advanceDeformable: the lattice gathers the rigid steps' time and takes only whole stable
    // steps, as many as the time holds, however the front cuts the rigid steps (the default
    // scene's lattice took one step per rigid step of 1.9 and 4.5 µs against its 6.8 µs).
    Simulation sim(wallScene(1.0, 0.5));
    double dtS = 0.0;
    sim.setStepObserver([&](const Simulation&, const StepRecord& r) { dtS = r.dtS; });
    double latticeTimeS = 0.0;
    int64_t rigidSteps = 0, latticeSteps = 0;
    while (sim.timeS() < 0.004) {
        sim.step();
        const int64_t particleSteps = sim.takeStepStats().latticeParticleSteps;
        const std::vector<DeformableBody>& stepped = sim.state().deformable.lattices;
        ASSERT_LE(stepped.size(), 1u) << "the wall broke apart before the check's end";
        if (stepped.empty()) continue;
        latticeTimeS += dtS;
        ++rigidSteps;
        latticeSteps += particleSteps / int64_t(stepped.front().lattice.particleCount());
    }
    ASSERT_EQ(sim.state().deformable.lattices.size(), 1u);
    const DeformableBody& wall = sim.state().deformable.lattices.front();
    const double stableS = wall.lattice.stableTimeStepS();
    std::printf("%lld rigid steps, %lld lattice steps of %.3g s, %.3g s gathered\n", static_cast<long long>(rigidSteps),
                static_cast<long long>(latticeSteps), stableS, wall.pendingS);
    EXPECT_NEAR(double(latticeSteps) * stableS + wall.pendingS, latticeTimeS, 1e-9 * latticeTimeS);
    EXPECT_LT(wall.pendingS, stableS);
    EXPECT_LT(latticeSteps, rigidSteps);
}

TEST(Deformable, MoreExplosiveBreaksMore)
{
    // Issue 17: with the pressure rule every link broke once a charge was big enough, whatever
    // more was added. From stress, more explosive makes more pieces and more crack surface.
    size_t previousBodies = 0;
    int64_t previousBrokenBonds = 0;
    for (const double tntKg : {0.1, 0.4, 1.6}) {
        Simulation sim(wallScene(tntKg, 0.5));
        sim.advanceTo(0.05);
        const int64_t broken = brokenBondsOf(sim);
        std::printf("%.1f kg TNT at 0.5 m: %zu bodies, %lld bonds broken (ground bonds included)\n", tntKg, sim.bodies().size(), static_cast<long long>(broken));
        EXPECT_GT(sim.bodies().size(), previousBodies) << tntKg << " kg";
        EXPECT_GT(broken, previousBrokenBonds + previousBrokenBonds / 2) << tntKg << " kg";
        previousBodies = sim.bodies().size();
        previousBrokenBonds = broken;
    }
}

namespace {

/// The UK damage relation for brick houses (issue 18; Jarrett 1968, as used by the UK Ministry
/// of Defence for explosives safety distances): the radius of a damage level k from W kg of TNT,
/// R = k W^(1/3) / [1 + (3175/W)²]^(1/6) (unit: m).
double ukDamageRadiusM(double k, double tntKg) { return k * std::cbrt(tntKg) / std::pow(1.0 + std::pow(3175.0 / tntKg, 2), 1.0 / 6.0); }

/// A storey of a house's wall: a strip `widthM` wide of a one-brick wall 0.225 m thick and 2.4 m
/// high, bonded to the ground and to a static slab on its head (the floor or roof that ties a
/// house wall's head) that bears `bearingPa` on it, 5 cm voxels; `tntKg` of TNT on the ground
/// `standoffM` in front of it.
Scene houseWallScene(double standoffM, double durationS, double tntKg = 100.0, double widthM = 1.125, double bearingPa = 0.0)
{
    const double heightM = 2.4, thicknessM = 0.225;
    nlohmann::json j = {
        {"voxel_size_m", kH}, {"duration_s", durationS}, {"frame_rate_hz", 24}, {"seed", 7},
        {"objects", {{{"name", "wall"}, {"primitive", {{"shape", "box"}, {"size_m", {widthM, thicknessM, heightM}}}},
                      {"position_m", {0, 0, heightM / 2}}, {"material", "mean-brick"}, {"anchor", "supports"}}}},
        {"materials", kMeanBrick},
        {"charges", {{{"position_m", {0, -standoffM - thicknessM / 2, 0}}, {"tnt_kg", tntKg}}}},
        {"fracture", {{"algorithm", "lattice"}}},
        {"lattice", {{"max_vibration_s", 0.05}}},
        {"colliders",
         {{{"position_m", {0, 0, heightM + 0.1}}, {"size_m", {widthM + 0.4, thicknessM + 0.4, 0.2}}, {"bearing_pressure_pa", bearingPa}}}},
    };
    return parseScene(j.dump(), "house-wall", ".");
}

/// The share of the wall's mass more than 0.25 m off its plane (unit: 1).
double massOffPlane(const Simulation& sim)
{
    double massKg = 0.0, offKg = 0.0;
    for (const Body& body : sim.bodies()) {
        massKg += body.mass.massKg;
        if (std::abs(body.motion.positionM.y()) > 0.25) offKg += body.mass.massKg;
    }
    return offKg / massKg;
}

/// The height of the wall's centre of mass, all its pieces together (unit: m).
double centreOfMassHeightM(const Simulation& sim)
{
    double massKg = 0.0, momentKgM = 0.0;
    for (const Body& body : sim.bodies()) {
        massKg += body.mass.massKg;
        momentKgM += body.mass.massKg * body.motion.positionM.z();
    }
    return momentKgM / massKg;
}

}  // namespace

TEST(Deformable, AHouseWallCollapsesAtTheDemolitionRadiusAndStandsAtTwiceTheUninhabitableRadius)
{
    // Issue 18, against experience: 100 kg gives R = 5.57 m for complete demolition (k = 3.8)
    // and 14.1 m for uninhabitable (k = 9.6). A house wall held at its base and head must come
    // down at the first and stand at twice the second.
    // Both carry two storeys' 0.1 MPa on their heads, as a house wall does (without it the far
    // wall, cracked off its base, sank 8 cm in 2 s).
    const double startM = 1.2;
    Simulation near(houseWallScene(ukDamageRadiusM(3.8, 100.0), 1.0, 100.0, 1.125, 1e5));
    near.advanceTo(1.0);
    Simulation far(houseWallScene(2.0 * ukDamageRadiusM(9.6, 100.0), 2.0, 100.0, 1.125, 1e5));
    far.advanceTo(2.0);
    std::printf("centre of mass from %.2f m: at R(3.8) %.2f m (%zu pieces) after 1 s; at 2 R(9.6) %.3f m (%zu) after 2 s\n", startM,
                centreOfMassHeightM(near), near.bodies().size(), centreOfMassHeightM(far), far.bodies().size());
    EXPECT_LT(centreOfMassHeightM(near), 0.5 * startM) << "collapsed";
    EXPECT_NEAR(centreOfMassHeightM(far), startM, 0.02) << "standing";
}

TEST(Deformable, AHouseWallCarryingItsFloorsStandsAtTwiceTheUninhabitableRadius)
{
    // Issue 47: a wall in a building carries the floors and roof above it, and that
    // precompression holds it. A storey 1.6 m wide under 50 kg of TNT at twice the UK damage
    // relation's uninhabitable radius (17.7 m, where houses are repairable): with nothing on its
    // head, 74 % of its mass ends more than 0.25 m off its plane; under two storeys' 0.1 MPa
    // (15–30 kN per metre of wall) it cracks and stays in its plane.
    Simulation sim(houseWallScene(2.0 * ukDamageRadiusM(9.6, 50.0), 1.5, 50.0, 1.6, 1e5));
    sim.advanceTo(1.5);
    std::printf("%zu pieces, %.0f %% of the mass off its plane, centre of mass at %.2f m\n", sim.bodies().size(), 100.0 * massOffPlane(sim),
                centreOfMassHeightM(sim));
    EXPECT_LT(massOffPlane(sim), 0.1);
}

TEST(Deformable, AnchorsHoldTheMaterialsTensileStrengthAndThenLetGo)
{
    // A 0.1 × 0.1 × 0.25 m brick column anchored at its base, pulled up by a body force that
    // grows slowly against its axial period (0.6 ms): the ground bonds must carry the material's
    // tensile strength over the base, ft A (the definition of strength), and no more. Undamped:
    // its damping's forces would take a share of the pull. Every bond alike: the mean strength.
    Material brick = test::withoutStrengthScatter(findMaterialPreset("brick-masonry"));
    brick.dampingRatio = 0.0;
    const double h = 0.025;
    Body column = test::boxBody(4, 4, 10, h, brick.densityKgM3, Eigen::Vector3d(0.0, 0.0, 0.125 - 0.5 * h));
    for (auto it = column.grid->beginValueOn(); it; ++it)
        if (it.getCoord().z() == 0) it.setValue(*it | kAnchorBit);
    refreshDerivedData(column);
    column.motion.positionM = Eigen::Vector3d(0.0, 0.0, 0.125);  // the base's faces on z = 0
    Lattice lattice = Lattice::fromBody(column, brick, test::groundAtZero());
    ASSERT_EQ(lattice.particleCount() - lattice.model().voxelParticleCount, 16u) << "one ground point per anchored voxel";
    const double strengthN = brick.tensileStrengthPa * 0.1 * 0.1;
    const double columnMassKg = lattice.model().particleMassKg * double(lattice.model().voxelParticleCount);
    const double rampS = 0.02, pullRate = 2.0 * strengthN / columnMassKg / rampS;  // reaches twice the strength at rampS
    const double dt = lattice.stableTimeStepS();
    double peakAnchorForceN = 0.0;
    for (double t = 0.0; t < rampS; t += dt) {
        for (size_t p = 0; p < lattice.model().voxelParticleCount; ++p)
            lattice.externalForceN[p] = Eigen::Vector3d(0.0, 0.0, lattice.model().particleMassKg * pullRate * t);
        lattice.step(dt);
        double anchorForceN = 0.0;
        for (size_t g = lattice.model().voxelParticleCount; g < lattice.particleCount(); ++g) anchorForceN += lattice.state.bondForceN[g].z();
        peakAnchorForceN = std::max(peakAnchorForceN, anchorForceN);
    }
    std::printf("anchors carried at most %.0f N, ft x base %.0f N (%+.1f %%)\n", peakAnchorForceN, strengthN,
                100.0 * (peakAnchorForceN / strengthN - 1.0));
    EXPECT_NEAR(peakAnchorForceN, strengthN, 0.1 * strengthN);
    const HandOff handed = handOff(column, lattice);
    EXPECT_EQ(handed.brokenAnchors, 16);
    ASSERT_EQ(handed.parts.size(), 1u);
    EXPECT_FALSE(handed.parts.front().anchored);
    EXPECT_GT(handed.parts.front().motion.linearVelocityMS.z(), 0.0);
}
