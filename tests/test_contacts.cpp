#include "TestUtil.h"

#include <spall/dynamics/ContactSolver.h>
#include <spall/dynamics/Contacts.h>
#include <spall/dynamics/DebrisScenes.h>
#include <spall/dynamics/Integrate.h>

#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <tbb/global_control.h>

#include <random>

using namespace spall;

namespace {

/// No gravity, no ground: only the bodies.
WorldSettings emptySpace()
{
    WorldSettings world;
    world.gravityMS2.setZero();
    world.ground.enabled = false;
    world.airDrag = AirDrag::None;  // no external force: the solver alone must keep momentum
    return world;
}

SleepSettings noSleep()
{
    SleepSettings s;
    s.enabled = false;
    return s;
}

Eigen::Vector3d totalLinearMomentum(const std::vector<Body>& bodies)
{
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (const Body& b : bodies) p += linearMomentum(b);
    return p;
}

Eigen::Vector3d totalAngularMomentum(const std::vector<Body>& bodies)
{
    Eigen::Vector3d l = Eigen::Vector3d::Zero();
    for (const Body& b : bodies) l += angularMomentumAboutOrigin(b);
    return l;
}

double totalKineticEnergy(const std::vector<Body>& bodies)
{
    double e = 0;
    for (const Body& b : bodies) e += kineticEnergyJ(b);
    return e;
}

/// The largest step the simulation would take: no voxel moves more than half a voxel.
double speedLimitedStep(const std::vector<Body>& bodies, double maxDt)
{
    double dt = maxDt;
    for (const Body& b : bodies)
        if (!b.anchored && maxVoxelSpeedMS(b) > 0) dt = std::min(dt, 0.5 * b.voxelSizeM / maxVoxelSpeedMS(b));
    return dt;
}

}  // namespace

TEST(Collisions, ThreeNarrowPhasesFindTheSameVoxelPairs)
{
    // Randomly placed and turned small bodies, kept only where no two voxels overlap by more than
    // a quarter voxel (deeper, the tree lookup also meets interior voxels the baselines never test).
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> pos(0.0, 0.6), angle(-3.14159, 3.14159);
    const double h = 0.1;
    int compared = 0;
    for (int trial = 0; trial < 300; ++trial) {
        std::vector<Body> bodies;
        for (int i = 0; i < 5; ++i) {
            const Eigen::Vector3d axis = Eigen::Vector3d(angle(rng), angle(rng), angle(rng)).normalized();
            bodies.push_back(test::boxBody(2 + i % 2, 2 + i % 2, 2 + i % 2, h, 2000.0, Eigen::Vector3d(pos(rng), pos(rng), pos(rng)), Eigen::Quaterniond(Eigen::AngleAxisd(angle(rng), axis))));
        }
        const std::vector<ContactManifold> reference = findBodyContacts(bodies, CollisionMethod::Pairwise);
        if (std::any_of(reference.begin(), reference.end(), [&](const ContactManifold& m) { return m.maxDepthM > 0.25 * h; })) continue;
        const std::vector<ContactManifold> buckets = findBodyContacts(bodies, CollisionMethod::Buckets);
        const std::vector<ContactManifold> tree = findBodyContacts(bodies, CollisionMethod::TreeLookup);
        ASSERT_EQ(buckets.size(), reference.size());
        ASSERT_EQ(tree.size(), reference.size());
        for (size_t k = 0; k < reference.size(); ++k) {
            for (const auto* other : {&buckets[k], &tree[k]}) {
                EXPECT_EQ(other->a, reference[k].a);
                EXPECT_EQ(other->b, reference[k].b);
                EXPECT_EQ(other->voxelContacts, reference[k].voxelContacts);
                EXPECT_NEAR(other->maxDepthM, reference[k].maxDepthM, 1e-12);
                EXPECT_LT((other->normal - reference[k].normal).norm(), 1e-9);
            }
        }
        compared += static_cast<int>(reference.size());
    }
    EXPECT_GT(compared, 10) << "too few touching pairs to compare";
}

TEST(Collisions, BroadPhaseFindsExactlyTheOverlappingSpheres)
{
    // Bodies of sizes spread over three decades, packed and scattered, some asleep or anchored:
    // the grid must return exactly what testing every pair returns.
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Body> bodies(600);
    for (size_t i = 0; i < bodies.size(); ++i) {
        Body& b = bodies[i];
        b.boundingRadiusM = 0.01 * std::pow(1000.0, unit(rng));
        const double extent = i < 300 ? 1.0 : 20.0;  // a packed cluster, then a scattered cloud
        b.motion.positionM = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * extent - Eigen::Vector3d::Constant(0.5 * extent);
        b.motion.asleep = unit(rng) < 0.2;
        b.anchored = unit(rng) < 0.05;
    }
    std::vector<BodyPair> expected;
    for (int i = 0; i < static_cast<int>(bodies.size()); ++i)
        for (int j = i + 1; j < static_cast<int>(bodies.size()); ++j) {
            const double reach = bodies[i].boundingRadiusM + bodies[j].boundingRadiusM;
            if ((bodies[i].motion.positionM - bodies[j].motion.positionM).norm() <= reach && pairCanInteract(bodies[i], bodies[j]))
                expected.push_back({i, j});
        }
    ASSERT_GT(expected.size(), 1000u);
    EXPECT_EQ(findCandidatePairs(bodies), expected);
}

TEST(Collisions, ManifoldOfAFlatContactIsNormalToTheFaces)
{
    // A 4^3 cube resting on a 6^3 cube, shifted sideways by a third of a voxel: every centre line
    // is oblique, but their depth-weighted mean is the face normal.
    const double h = 0.1;
    std::vector<Body> bodies{test::boxBody(6, 6, 6, h, 2000.0, Eigen::Vector3d(0, 0, 0)), test::boxBody(4, 4, 4, h, 2000.0, Eigen::Vector3d(0.03, 0.0, 0.5 * (6 + 4) * h - 0.1 * h))};
    const std::vector<ContactManifold> m = findBodyContacts(bodies, CollisionMethod::TreeLookup);
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].a, 0);
    EXPECT_LT((m[0].normal - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9) << m[0].normal.transpose();
    EXPECT_EQ(m[0].points.size(), 4u);
}

TEST(Collisions, ManifoldPointsStayPutWhileDepthsChange)
{
    // A resting patch's depths differ by rounding from step to step. The four points must not
    // follow them: the warm start finds last step's impulses only at points within a quarter
    // voxel, and points that jumped across a jagged patch left a heavy slab rocking. Five draws
    // of random depths over one 10 x 6 patch give the same four points, and they span it.
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> depth(-0.05, 0.05);
    std::vector<std::vector<Eigen::Vector3d>> chosen;
    for (int draw = 0; draw < 5; ++draw) {
        std::vector<VoxelContact> patch;
        for (int i = 0; i < 10; ++i)
            for (int j = 0; j < 6; ++j) patch.push_back({Eigen::Vector3d(i, j, 0), Eigen::Vector3d::UnitZ(), depth(rng)});
        std::vector<Eigen::Vector3d> points;
        for (size_t k : spanningPoints(patch, Eigen::Vector3d::UnitZ())) points.push_back(patch[k].pointM);
        chosen.push_back(points);
    }
    ASSERT_EQ(chosen[0].size(), 4u);
    for (const Eigen::Vector3d& corner : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(9, 0, 0), Eigen::Vector3d(0, 5, 0), Eigen::Vector3d(9, 5, 0)})
        EXPECT_TRUE(std::find(chosen[0].begin(), chosen[0].end(), corner) != chosen[0].end()) << corner.transpose();
    for (int draw = 1; draw < 5; ++draw) EXPECT_EQ(chosen[draw], chosen[0]) << "draw " << draw;
}

TEST(Collisions, BodiesOfDifferentVoxelSizesAreAnInputError)
{
    // The contact code takes one voxel size for every body; a mix is refused, not mis-simulated.
    std::vector<Body> bodies{test::boxBody(2, 2, 2, 0.1, 2000.0), test::boxBody(2, 2, 2, 0.05, 2000.0, Eigen::Vector3d(1, 0, 0))};
    bodies[1].id = 1;
    try {
        rigidBodySimulation(bodies, emptySpace(), CollisionSettings(), noSleep(), 1e-3);
        FAIL() << "a mix of voxel sizes was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("body 1 has voxel size 0.05"), std::string::npos) << e.what();
    }
}

TEST(Collisions, HeadOnImpactMatchesRestitutionAndConservesMomentum)
{
    // Equal cubes face to face along x: v1' = (1 - e) v / 2, v2' = (1 + e) v / 2.
    const double h = 0.1, v = 3.0;
    for (double e : {0.0, 0.5, 1.0}) {
        std::vector<Body> bodies{test::boxBody(3, 3, 3, h, 2000.0, Eigen::Vector3d(0, 0, 0)), test::boxBody(3, 3, 3, h, 2000.0, Eigen::Vector3d(0.3 + 0.5 * h, 0, 0))};
        bodies[0].motion.linearVelocityMS = Eigen::Vector3d(v, 0, 0);
        CollisionSettings cs;
        cs.restitution = e;
        cs.friction = 0.0;
        // (Angular momentum is zero here by symmetry; the free cluster below checks it.)
        const Eigen::Vector3d p0 = totalLinearMomentum(bodies);
        const double energy0 = totalKineticEnergy(bodies);
        Simulation sim = rigidBodySimulation(bodies, emptySpace(), cs, noSleep(), 1e-3);
        for (int i = 0; i < 200; ++i) sim.step();
        bodies = sim.bodies();
        EXPECT_NEAR(bodies[0].motion.linearVelocityMS.x(), 0.5 * (1 - e) * v, 0.01 * v) << "e = " << e;
        EXPECT_NEAR(bodies[1].motion.linearVelocityMS.x(), 0.5 * (1 + e) * v, 0.01 * v) << "e = " << e;
        EXPECT_LT((totalLinearMomentum(bodies) - p0).norm(), 1e-12 * p0.norm());
        EXPECT_LE(totalKineticEnergy(bodies), energy0 * (1 + 1e-9));
    }
}

TEST(Collisions, EnergyNeverGrowsAndMomentumIsKeptInAFreeCluster)
{
    // Tumbling fragments packed together in empty space, no external force: every contact may
    // only take energy out, and impulses come in equal and opposite pairs, so linear and angular
    // momentum are kept. (Angular momentum is compared right after the solve, at the poses the
    // impulses acted on: the position correction afterwards moves centres, which changes r x p
    // but no velocity.)
    DebrisScene cloud = makeExplosionCloud(27, 3, 0.1, 2.0, 11);
    std::vector<Body>& bodies = cloud.bodies;
    for (Body& b : bodies) b.motion.linearVelocityMS = -b.motion.linearVelocityMS;  // inwards: they collide
    const Eigen::Vector3d p0 = totalLinearMomentum(bodies);
    double energy = totalKineticEnergy(bodies);
    double t = 0, worstAngular = 0;
    int64_t contacts = 0;
    const WrenchFunction none = [](double, const Eigen::Vector3d&, const Eigen::Quaterniond&, const Eigen::Vector3d&,
                                   const Eigen::Vector3d&) { return Wrench(); };
    for (int i = 0; i < 300; ++i) {
        const double dt = speedLimitedStep(bodies, 1.0 / 240);
        for (Body& b : bodies) integrateBody(b, t, dt, Integrator::SemiImplicitEuler, none);
        const Eigen::Vector3d before = totalAngularMomentum(bodies);
        const ContactSet found = detectContacts(bodies, emptySpace(), CollisionSettings(), noSleep());
        contacts += found.bodyContacts;
        ContactCache cold;  // no warm start: every impulse comes from this step's contacts
        solveContacts(bodies, found, emptySpace(), CollisionSettings(), dt, cold);
        worstAngular = std::max(worstAngular, (totalAngularMomentum(bodies) - before).norm());
        correctPositions(bodies, found, emptySpace());
        t += dt;
        const double now = totalKineticEnergy(bodies);
        ASSERT_LE(now, energy * (1 + 1e-9)) << "step " << i;
        energy = now;
    }
    EXPECT_GT(contacts, 100);
    const double scale = totalKineticEnergy(bodies) > 0 ? bodies.size() * bodies[0].mass.massKg * 2.0 : 1.0;
    EXPECT_LT((totalLinearMomentum(bodies) - p0).norm(), 1e-11 * scale);
    EXPECT_LT(worstAngular, 1e-11 * scale);
}

TEST(Collisions, NoTunnellingAt500MetresPerSecond)
{
    // Into the ground, into a one-voxel-thin anchored plate, and into each other.
    const double h = 0.05, v = 500.0;
    WorldSettings world;
    std::vector<Body> bodies;
    bodies.push_back(test::boxBody(2, 2, 2, h, 2000.0, Eigen::Vector3d(0, 0, 1.0)));
    bodies.back().motion.linearVelocityMS = Eigen::Vector3d(0, 0, -v);
    Body plate = test::boxBody(12, 12, 1, h, 2000.0);
    plate.motion.positionM = Eigen::Vector3d(3.0, 0, 1.0);
    plate.motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()));  // its normal along x
    plate.anchored = true;
    bodies.push_back(plate);
    bodies.push_back(test::boxBody(2, 2, 2, h, 2000.0, Eigen::Vector3d(2.5, 0, 1.0)));
    bodies.back().motion.linearVelocityMS = Eigen::Vector3d(v, 0, 0);
    bodies.push_back(test::boxBody(2, 2, 2, h, 2000.0, Eigen::Vector3d(6.0, 0, 1.0)));
    bodies.back().motion.linearVelocityMS = Eigen::Vector3d(v, 0, 0);
    bodies.push_back(test::boxBody(2, 2, 2, h, 2000.0, Eigen::Vector3d(7.0, 0, 1.0)));
    bodies.back().motion.linearVelocityMS = Eigen::Vector3d(-v, 0, 0);
    Simulation sim = rigidBodySimulation(bodies, world, CollisionSettings(), SleepSettings(), 1.0 / 240);
    for (int i = 0; i < 4000 && sim.timeS() < 0.02; ++i) {
        sim.step();
        const std::vector<Body>& now = sim.bodies();
        for (const Body& b : now) ASSERT_TRUE(b.motion.positionM.allFinite() && b.motion.linearVelocityMS.allFinite() && b.motion.angularVelocityRadS.allFinite());
        ASSERT_GT(now[0].motion.positionM.z(), 0.0) << "through the ground";
        ASSERT_LT(now[2].motion.positionM.x(), 3.0) << "through the plate";
        ASSERT_LT(now[3].motion.positionM.x(), now[4].motion.positionM.x()) << "through each other";
    }
    const double t = sim.timeS();
    EXPECT_GE(t, 0.02);
}

TEST(Collisions, AStepIsShortenedOnlyWhileItWouldDeepenAnOverlap)
{
    // tunnellingSpeedMS: a pair 0.4 voxel into each other closing at 0.1 m/s (a piece wedged in
    // a notch of another, jittering) goes 0.008 voxel deeper in a 1/240 s step, so a shorter step
    // does nothing for it; at 2 m/s it goes 0.17 voxel deeper, and the step halves until it
    // would go no more than a twentieth of a voxel deeper (1/960 s).
    const double h = 0.05;
    const WorldSettings world = emptySpace();
    for (const double closingMS : {0.1, 2.0}) {
        std::vector<Body> bodies{test::boxBody(2, 2, 2, h, 2000.0), test::boxBody(2, 2, 2, h, 2000.0, Eigen::Vector3d(2 * h - 0.4 * h, 0, 0))};
        bodies[0].motion.linearVelocityMS.x() = 0.5 * closingMS;
        bodies[1].motion.linearVelocityMS.x() = -0.5 * closingMS;
        const ContactSet contacts = detectContacts(bodies, world, CollisionSettings(), noSleep());
        ASSERT_EQ(contacts.manifolds.size(), 1u);
        const double depthM = contacts.manifolds[0].maxDepthM;
        // Faster than a resting contact either way:
        EXPECT_EQ(deepestClosingPenetrationM(bodies, contacts, impactSpeedMS(world, 1.0 / 240)), depthM) << closingMS;
        // ... but only the faster one deepens the overlap enough in a step to shorten it:
        EXPECT_EQ(deepestClosingPenetrationM(bodies, contacts, tunnellingSpeedMS(world, 1.0 / 240, h)), closingMS > 1.0 ? depthM : 0.0) << closingMS;
        EXPECT_EQ(deepestClosingPenetrationM(bodies, contacts, tunnellingSpeedMS(world, 1.0 / 960, h)), 0.0) << closingMS;
    }
}

TEST(Collisions, AnOverlapThatIsNotClosingIsLeftToThePositionCorrectionNotTheStep)
{
    // Pieces can be born overlapping (a lattice hands off pieces whose rigid fits overlap by a
    // few millimetres at their crack): a shorter step does not separate them, the position
    // correction does. Two cubes 0.4 voxel into each other (beyond the 0.25 tolerance).
    const double h = 0.05;
    auto pair = [&](double closingMS) {
        std::vector<Body> bodies{test::boxBody(2, 2, 2, h, 2000.0), test::boxBody(2, 2, 2, h, 2000.0, Eigen::Vector3d(2 * h - 0.4 * h, 0, 0))};
        bodies[0].motion.linearVelocityMS.x() = 0.5 * closingMS;
        bodies[1].motion.linearVelocityMS.x() = -0.5 * closingMS;
        return bodies;
    };
    const WorldSettings world = emptySpace();
    for (const double closingMS : {0.0, -1.0, 2.0}) {
        std::vector<Body> bodies = pair(closingMS);
        const ContactSet contacts = detectContacts(bodies, world, CollisionSettings(), noSleep());
        ASSERT_EQ(contacts.manifolds.size(), 1u);
        EXPECT_NEAR(contacts.manifolds[0].maxDepthM, 0.4 * h, 1e-9);
        const double closing = deepestClosingPenetrationM(bodies, contacts, impactSpeedMS(world, 1.0 / 240));
        EXPECT_EQ(closing, closingMS > 0 ? contacts.manifolds[0].maxDepthM : 0.0) << closingMS << " m/s";
    }
    // At rest: full steps while the correction pushes them apart.
    Simulation sim = rigidBodySimulation(pair(0.0), world, CollisionSettings(), noSleep(), 1.0 / 240);
    double shortest = 1.0;
    sim.setStepObserver([&](const Simulation&, const StepRecord& r) { shortest = std::min(shortest, r.dtS); });
    for (int i = 0; i < 10; ++i) sim.step();
    EXPECT_EQ(shortest, 1.0 / 240);
    std::vector<Body> settled = sim.bodies();
    const ContactSet after = detectContacts(settled, world, CollisionSettings(), noSleep());
    for (const ContactManifold& m : after.manifolds) EXPECT_LT(m.maxDepthM, 0.25 * h);
}

TEST(Collisions, PileOfAThousandFragmentsSettlesAndSleeps)
{
    // The generated pile loosened: layers 30 % further apart and every fragment tumbled, so it
    // falls into a jumble before it can rest.
    DebrisScene pile = makeDebrisPile(1000, 2, 0.05, 3);
    std::vector<Body>& bodies = pile.bodies;
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (Body& b : bodies) {
        b.motion.positionM.z() *= 1.3;
        b.motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * unit(rng), Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized())) * b.motion.orientation;
    }
    for (StaticBox& wall : pile.world.colliders) {
        wall.halfExtentM.z() *= 2.0;
        wall.centreM.z() *= 2.0;
    }
    Simulation sim = rigidBodySimulation(bodies, pile.world, CollisionSettings(), SleepSettings(), 1.0 / 240, true);
    double peak = 0, energy = 0;
    for (int step = 0; step < 240 * 10; ++step) {
        sim.step();
        energy = 0;
        for (const Body& b : sim.bodies()) energy += kineticEnergyJ(b);
        peak = std::max(peak, energy);
        if (std::all_of(sim.bodies().begin(), sim.bodies().end(), [](const Body& b) { return b.motion.asleep; })) break;
    }
    const double t = sim.timeS();
    bodies = sim.bodies();
    const auto asleep = std::count_if(bodies.begin(), bodies.end(), [](const Body& b) { return b.motion.asleep; });
    EXPECT_GE(asleep, 990) << "after " << t << " s";
    EXPECT_LT(energy, 1e-4 * peak);
    for (const Body& b : bodies) EXPECT_GT(b.motion.positionM.z(), 0.0);
}

TEST(Collisions, SameResultWithOneAndTwoThreads)
{
    // Large enough that the solver cuts the pile in two halves solved side by side.
    int64_t fewestContacts = std::numeric_limits<int64_t>::max();
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        DebrisScene pile = makeDebrisPile(1500, 3, 0.05, 9);
        Simulation sim = rigidBodySimulation(pile.bodies, pile.world, CollisionSettings(), SleepSettings(), 1.0 / 240, true);
        sim.setStepObserver([&](const Simulation&, const StepRecord& r) { fewestContacts = std::min(fewestContacts, r.solverContacts); });
        for (int i = 0; i < 40; ++i) sim.step();
        return sim.bodies();
    };
    const std::vector<Body> one = run(1), two = run(2);
    EXPECT_GT(fewestContacts, 4096);
    ASSERT_EQ(one.size(), two.size());
    for (size_t i = 0; i < one.size(); ++i) {
        EXPECT_EQ(one[i].motion.positionM, two[i].motion.positionM) << i;
        EXPECT_EQ(one[i].motion.orientation.coeffs(), two[i].motion.orientation.coeffs()) << i;
        EXPECT_EQ(one[i].motion.linearVelocityMS, two[i].motion.linearVelocityMS) << i;
    }
}

TEST(Collisions, PiecesOfAJaggedCrackComeToRest)
{
    // A slab on the ground cut in two along a jagged crack, the pieces pressed a fifth of a voxel
    // into each other and one turned a little (as a lattice hands off pieces whose rigid fits
    // overlap at their crack): the position correction separates them, and they sleep.
    const double h = 0.05;
    Body slab = test::boxBody(16, 8, 2, h, 2000.0);
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> crackAt(6, 9);
    std::vector<int> crack(8);
    for (int& c : crack) c = crackAt(rng);
    {
        auto acc = slab.grid->getAccessor();
        for (int j = 0; j < 8; ++j)
            for (int k = 0; k < 2; ++k) {
                breakLink(acc, openvdb::Coord(crack[j], j, k), kPosX);
                if (j + 1 < 8)
                    for (int i = 0; i < 16; ++i)
                        if ((i > crack[j]) != (i > crack[j + 1])) breakLink(acc, openvdb::Coord(i, j, k), kPosY);
            }
    }
    std::vector<Body> pieces = splitBody(slab);
    ASSERT_EQ(pieces.size(), 2u);
    for (size_t i = 0; i < pieces.size(); ++i) pieces[i].id = int64_t(i);
    pieces[1].motion.positionM.x() -= 0.2 * h;
    pieces[1].motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ())) * pieces[1].motion.orientation;
    WorldSettings world;
    world.ground.offsetM = -0.5 * h;
    Simulation sim = rigidBodySimulation(pieces, world, CollisionSettings(), SleepSettings(), 1.0 / 240);
    while (sim.timeS() < 2.0) sim.step();
    for (const Body& b : sim.bodies()) EXPECT_TRUE(b.motion.asleep) << b.id;
    std::vector<Body> settled = sim.bodies();
    for (const ContactManifold& m : detectContacts(settled, world, CollisionSettings(), noSleep()).manifolds) EXPECT_LT(m.maxDepthM, 0.25 * h);
}
