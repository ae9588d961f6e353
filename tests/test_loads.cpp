// The loads stage against independent references: Kingery–Bulmash reflected impulse, the UFC
// 3-340-02 front-minus-rear procedure worked by hand, the CFD clearing ratios of
// shared/reference/blast-loads-cfd.md, and properties that must hold.
#include "TestUtil.h"

#include <spall/loads/BlastLoads.h>
#include <spall/loads/Exposure.h>
#include <spall/loads/FacePulse.h>
#include <spall/loads/ObliqueReflection.h>
#include <spall/analysis/StructureLoads.h>
#include <spall/scene/Scene.h>

#include <gtest/gtest.h>

#include <random>

using namespace spall;

namespace {

/// The blast impulse (unit: N s) and angular impulse on a body held still through the whole
/// wave, in steps of `dtS` from detonation.
Wrench impulseOnHeldBody(const Body& body, const BlastField& field, const LoadSettings& settings, const StaticWorld& ground,
                         double dtS, double untilS)
{
    Wrench total;
    for (double t = 0; t < untilS; t += dtS) {
        const auto windows = field.openWindows(t);
        const BlastLoads loads(field, windows, settings, ground);
        const Wrench w = loads.stepWrench(body, t, dtS);
        total.forceN += w.forceN * dtS;
        total.torqueNm += w.torqueNm * dtS;
    }
    return total;
}

/// Sum over the body's exposed faces whose centre satisfies `select` of the impulse per area
/// pushing into them, times their area (unit: N s), from detonation to `untilS`.
template <typename Select>
double faceImpulseOn(const Body& body, const BlastField& field, const StaticWorld& ground, double dtS, double untilS, Select&& select)
{
    double total = 0;
    const double area = body.voxelSizeM * body.voxelSizeM;
    for (double t = 0; t < untilS; t += dtS) {
        const auto windows = field.openWindows(t);
        const BlastLoads loads(field, windows, LoadSettings(), ground);
        const std::vector<double> perFace = loads.faceImpulsesPaS(body, t, std::min(dtS, untilS - t));
        for (size_t i = 0; i < perFace.size(); ++i)
            if (select(body.exposedFaces[i])) total += perFace[i] * area;
    }
    return total;
}

}  // namespace

TEST(Loads, LargeWallAtNormalIncidenceTakesTheKingeryBulmashReflectedImpulse)
{
    // A 30.5 m square wall 3 m from 1 kg in free air: at its centre clearing takes about 1 % of
    // the impulse (tc ~ 60 ms against T+ ~ 2.6 ms), so the face there takes the normally
    // reflected impulse Ir of the direct Kingery–Bulmash fit (ARBRL-TR-02555).
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 1.0, 0.0, BurstType::FreeAir}}, BlastSettings());
    const double h = 0.5;
    const Body wall = test::boxBody(1, 61, 61, h, 2000.0, Eigen::Vector3d(3.0 + 0.5 * h, 0, 0));
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 1.0, 3.0);
    const double impulse = faceImpulseOn(wall, field, StaticWorld(), p.positiveDurationS / 200, p.arrivalTimeS + p.positiveDurationS,
                                         [](const ExposedFace& f) { return f.voxel == openvdb::Coord(0, 30, 30) && f.face == kNegX; });
    EXPECT_NEAR(impulse / (h * h), p.reflectedImpulsePaS, 0.05 * p.reflectedImpulsePaS);
}

TEST(Loads, TiltedPlateIsPushedAlongItsNormal)
{
    // A plate turned 45 degrees from the line to the charge. Its edges take a little load too,
    // so the push is within a few degrees of the normal; the paper's rule pushes along the
    // radius, 45 degrees off.
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 5.0, 0.0, BurstType::FreeAir}}, BlastSettings());
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()));
    const Body plate = test::boxBody(1, 40, 40, 0.1, 2000.0, Eigen::Vector3d(5, 0, 0), turn);
    const Eigen::Vector3d normal = turn * Eigen::Vector3d::UnitX();
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 5.0, 5.0);
    const double until = p.arrivalTimeS + 2 * p.positiveDurationS, dt = p.positiveDurationS / 100;
    auto degreesOff = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::acos(std::abs(a.normalized().dot(b.normalized()))) * 180 / M_PI; };
    const Wrench engineering = impulseOnHeldBody(plate, field, LoadSettings(), StaticWorld(), dt, until);
    EXPECT_LT(degreesOff(engineering.forceN, normal), 3.0);
    EXPECT_GT(engineering.forceN.dot(normal), 0.0);
    const Wrench paper = impulseOnHeldBody(plate, field, LoadSettings{LoadModel::Paper}, StaticWorld(), dt, until);
    EXPECT_GT(degreesOff(paper.forceN, normal), 40.0);
}

TEST(Loads, NothingEndsMovingTowardAFreeAirCharge)
{
    // A 0.2 m cube at growing distances from 8 kg: engulfed, it feels the negative phase on
    // every face, which nearly cancels; the net push stays away from the charge, and the
    // negative phase changes it by little. (The paper's rule, suction on the front face only,
    // pulls it back beyond Z ~ 2.8.)
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 8.0, 0.0, BurstType::FreeAir}}, BlastSettings());
    for (double distance : {2.0, 5.0, 10.0, 20.0, 27.0, 40.0}) {
        const Body cube = test::boxBody(2, 2, 2, 0.1, 2000.0, Eigen::Vector3d(distance, 0.03, -0.02));
        const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 8.0, distance);
        const BlastParameters rear = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 8.0, distance + 0.3);
        const double dt = p.positiveDurationS / 50, end = p.arrivalTimeS + p.positiveDurationS + p.negativeDurationS + 0.01;
        double momentum = 0, afterPositivePhase = 0;
        for (double t = 0; t < end; t += dt) {
            const auto windows = field.openWindows(t);
            momentum += BlastLoads(field, windows, LoadSettings(), StaticWorld()).stepWrench(cube, t, dt).forceN.x() * dt;
            if (t < rear.arrivalTimeS + rear.positiveDurationS) afterPositivePhase = momentum;
        }
        EXPECT_GT(momentum, 0.0) << distance << " m";
        EXPECT_NEAR(momentum, afterPositivePhase, 0.2 * afterPositivePhase) << distance << " m";
    }
}

TEST(Loads, SmallCubeMatchesTheUfcFrontMinusRearProcedure)
{
    // UFC 3-340-02 §2-15.3 worked by hand for a 0.4 m cube 10 m from 10 kg (free air): the front
    // face's pressure falls linearly from Pr to the stagnation pressure Ps + q over the clearing
    // time tc = 4S/((1 + S/G) U), S = G = L/2, then follows the stagnation pressure down a
    // triangle of fictitious duration tof = 2 Is / Ps; the rear face's rises over 4S/U from the
    // arrival there to Ps + Cd q (Cd = -0.25) and falls on the same triangle. Positive phases only.
    const double tnt = 10.0, distance = 10.0, side = 0.4, p0 = 101325.0;
    const BlastField field({Charge{Eigen::Vector3d::Zero(), tnt, 0.0, BurstType::FreeAir}}, BlastSettings());
    const Body cube = test::boxBody(4, 4, 4, 0.1, 2000.0, Eigen::Vector3d(distance + side / 2, 0, 0));
    const BlastParameters front = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, tnt, distance);
    const BlastParameters rear = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, tnt, distance + side);
    const double u = front.shockSpeedMS, tc = 4 * (side / 2) / (2 * u);
    const double ps = front.peakOverpressurePa, q = 2.5 * ps * ps / (ps + 7 * p0), tof = 2 * front.positiveImpulsePaS / ps;
    const double stagnationAtTc = (ps + q) * (1 - tc / tof);
    const double frontByHand = std::min(0.5 * (front.reflectedPressurePa + stagnationAtTc) * tc + 0.5 * stagnationAtTc * (tof - tc),
                                        front.reflectedImpulsePaS);
    const double rise = 4 * (side / 2) / u, psRear = rear.peakOverpressurePa, qRear = 2.5 * psRear * psRear / (psRear + 7 * p0);
    const double tofRear = 2 * rear.positiveImpulsePaS / psRear, rearPeak = (psRear - 0.25 * qRear) * (1 - rise / tofRear);
    const double rearByHand = 0.5 * rearPeak * rise + 0.5 * rearPeak * (tofRear - rise);
    const double byHand = (frontByHand - rearByHand) * side * side;

    const double dt = front.positiveDurationS / 200;
    const double frontImpulse = faceImpulseOn(cube, field, StaticWorld(), dt, front.arrivalTimeS + front.positiveDurationS,
                                              [](const ExposedFace& f) { return f.face == kNegX; });
    const double rearImpulse = faceImpulseOn(cube, field, StaticWorld(), dt, rear.arrivalTimeS + rear.positiveDurationS,
                                             [](const ExposedFace& f) { return f.face == kPosX; });
    std::printf("0.4 m cube: front %.3f N s (by hand %.3f), rear %.3f N s (by hand %.3f)\n", frontImpulse, frontByHand * side * side, rearImpulse,
                rearByHand * side * side);
    EXPECT_NEAR(frontImpulse - rearImpulse, byHand, 0.2 * byHand) << "front " << frontImpulse << " rear " << rearImpulse;
}

TEST(Loads, FiniteWallClearsAsTheCfdReferenceSays)
{
    // shared/reference/blast-loads-cfd.md: walls of height H 2 m from a 0.36 kg surface burst
    // take, over their face, this part of the front impulse a very tall wall takes over the
    // same face (positive phase): 0.875 for H = 0.5 m, 0.994 for H = 2 m. Long walls (20 m),
    // so only the top edge clears, as in the axisymmetric reference.
    const StaticWorld ground = test::groundAtZero();
    const double h = 0.1, p0 = 101325.0;
    auto wallOfHeight = [&](int voxels) { return test::boxBody(1, 200, voxels, h, 2000.0, Eigen::Vector3d(2.0 + 0.5 * h, 0, 0.5 * h * voxels)); };
    const Body tall = wallOfHeight(35);
    // The central strip of the lowest `voxels` voxels, front faces: voxels 98..101 across the middle.
    auto strip = [](const ExposedFace& f, int voxels) { return f.face == kNegX && f.voxel.y() >= 98 && f.voxel.y() <= 101 && f.voxel.z() < voxels; };

    // End to end, on Kingery-Bulmash's wave from the charge: 0.966 for the 0.5 m wall, 10.4 %
    // high. A quarter of that is the source's, not the clearing's: the reference's is not TNT,
    // and its reflected impulse is 3.52 times its side-on impulse at 2 m where Kingery-Bulmash's
    // is 2.66, so more of its reflected impulse is the excess that clearing takes.
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 0.365, 0.0, BurstType::Surface}}, BlastSettings());
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::Surface, 0.365, 2.0);
    const double dt = p.positiveDurationS / 200, until = p.arrivalTimeS + p.positiveDurationS;
    auto lowest = [&](const ExposedFace& f) { return strip(f, 5); };
    const double endToEnd = faceImpulseOn(wallOfHeight(5), field, ground, dt, until, lowest) / faceImpulseOn(tall, field, ground, dt, until, lowest);
    EXPECT_NEAR(endToEnd, 0.875, 0.12 * 0.875) << endToEnd;

    // The clearing itself: the same faces, outlines and face model on the reference's own wave
    // at 2 m (its table: Ps 151 kPa, is 72.8 Pa s, T+ 1.44 ms; the large wall's Pr 486 kPa, ir
    // 256 Pa s; the shock speed from Ps by Rankine-Hugoniot in its air, gamma 1.4 at 288 K).
    PointPulse wave;
    wave.peakOverpressurePa = 151e3, wave.positiveDurationS = 1.44e-3, wave.reflectedPeakPa = 486e3;
    wave.decayCoefficient = solveDecayCoefficient(72.8 / (wave.peakOverpressurePa * wave.positiveDurationS));
    wave.reflectedDecayCoefficient = solveDecayCoefficient(256.0 / (wave.reflectedPeakPa * wave.positiveDurationS));
    wave.shockSpeedMS = std::sqrt(1.4 * 287.05 * 288.0) * std::sqrt(1.0 + 6.0 * wave.peakOverpressurePa / (7.0 * p0));
    auto frontImpulse = [&](const Body& wall, int voxels) {
        const Silhouette outline = silhouetteOf({&wall}, {}, Eigen::Vector3d::Zero(), wave.shockSpeedMS, ground.ground);
        double total = 0;
        for (const ExposedFace& f : wall.exposedFaces) {
            if (!strip(f, voxels)) continue;
            const Eigen::Vector3d centre = wall.motion.positionM + wall.voxelOffsetM(f.voxel) - Eigen::Vector3d(0.5 * h, 0, 0);
            const FaceExposure face = faceExposure(wave, centre.normalized().x(), outline.clearingTimeS(), outline.rearRiseTimeS(), p0);
            total += faceImpulsePaS(wave, face, 0.0, wave.positiveDurationS, p0);
        }
        return total;
    };
    const double half = frontImpulse(wallOfHeight(5), 5) / frontImpulse(tall, 5), two = frontImpulse(wallOfHeight(20), 20) / frontImpulse(tall, 20);
    std::printf("front impulse against a tall wall's: 0.5 m wall %.3f end to end (CFD 0.875); on the CFD's wave 0.5 m %.3f, 2 m %.3f (0.994)\n",
                endToEnd, half, two);
    EXPECT_NEAR(half, 0.875, 0.1 * 0.875);
    EXPECT_NEAR(two, 0.994, 0.1 * 0.994);
    EXPECT_LT(half, two);
}

TEST(Exposure, FacesBetweenTouchingLayersTouchNoAirAndTheLayersAreOneGroup)
{
    // Three 2 m x 0.1 m x 2 m layers pressed together: each of the 400 voxel faces between two
    // layers is covered on both sides, and the three clear as one group. The third layer sits
    // 0.3 voxel off the first two's lattice sideways, as pieces of another object may.
    const double h = 0.1;
    std::vector<Body> layers;
    for (int k = 0; k < 3; ++k) layers.push_back(test::boxBody(20, 1, 20, h, 1800.0, Eigen::Vector3d(k == 2 ? 0.03 : 0.0, 4.05 + h * k, 0)));
    const Exposure exposure(layers, std::vector<char>(layers.size(), 1));
    for (size_t b = 0; b < layers.size(); ++b) {
        int covered = 0;
        for (size_t f = 0; f < layers[b].exposedFaces.size(); ++f) covered += exposure.covered(b, f);
        EXPECT_EQ(covered, b == 1 ? 800 : 400) << "layer " << b;
        EXPECT_EQ(exposure.groupOf()[b], 0u) << "layer " << b;
    }
    EXPECT_FALSE(exposure.alone(0));
}

TEST(Loads, SlabTakesTheSameImpulseIntactOrInTouchingLayers)
{
    // Issue 16's slab: 2 m x 0.3 m x 2 m brick, 0.1 m voxels, free in the air 4 m from 20 kg.
    // Broken into three layers that still touch, the faces between them touch no air and the
    // layers clear as one outline: the momentum is the intact slab's (it was 2.9 times it when
    // every layer took the full reflected load on its front face).
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 20.0, 0.0, BurstType::FreeAir}}, BlastSettings());
    const double h = 0.1;
    std::vector<Body> intact{test::boxBody(20, 3, 20, h, 1800.0, Eigen::Vector3d(0, 4.15, 0))};
    std::vector<Body> layers;
    for (int k = 0; k < 3; ++k) {
        layers.push_back(test::boxBody(20, 1, 20, h, 1800.0, Eigen::Vector3d(0, 4.05 + h * k, 0)));
        layers.back().id = k;
    }
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 20.0, 4.0);
    const double dt = p.positiveDurationS / 100, until = p.arrivalTimeS + p.positiveDurationS + p.negativeDurationS;
    auto momentum = [&](const std::vector<Body>& bodies) {
        Eigen::Vector3d total = Eigen::Vector3d::Zero();
        const std::vector<char> loaded(bodies.size(), 1);
        for (double t = 0; t < until; t += dt) {
            const auto windows = field.openWindows(t);
            for (const Wrench& w : BlastLoads(field, windows, LoadSettings(), StaticWorld()).stepWrenches(bodies, loaded, t, dt))
                total += w.forceN * dt;
        }
        return total;
    };
    const Eigen::Vector3d whole = momentum(intact), broken = momentum(layers);
    std::printf("slab momentum: intact %.1f N s, in touching layers %.1f N s\n", whole.y(), broken.y());
    EXPECT_GT(whole.y(), 0.0);
    // docs/accuracy.md: -0.3 %; the bound is three times that (15 % let a regression that
    // covered no face at all through for two days).
    EXPECT_NEAR(broken.y(), whole.y(), 0.01 * whole.y()) << "intact " << whole.y() << " N s, in layers " << broken.y() << " N s";
}

TEST(Loads, BoxBehindABlastWallTakesTheDiffractedLoad)
{
    // shared/reference/blast-loads-cfd.md: 0.2 m blocks behind a 1 m high, 0.1 m thick barrier
    // whose front face is 2 m from a 0.36 kg surface burst (the barrier a long static box):
    // T1 0.3 m behind it at mid-height, T2 1.4 m behind it on the ground. With / without the
    // barrier the CFD gives, for the block's front face and for its net push:
    // T1 0.17-0.24 and 0.09, T2 0.476 and 0.376. spall loads the shadowed faces with the wave
    // diffracted over the barrier's top (loads/Diffraction.h), and as UFC 3-340-02 loads a
    // building's roof and rear, with its side-on pressure and drag and no reflection: T1 0.205
    // and 0.105, T2 0.39 and 0.30. Reflecting the diffracted wave as a shock gave T1's net push
    // twice the CFD's (0.18).
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 0.365, 0.0, BurstType::Surface}}, BlastSettings());
    const StaticWorld open = test::groundAtZero();
    StaticWorld walled = open;
    walled.boxes.push_back({Eigen::Vector3d(2.05, 0, 0.5), Eigen::Vector3d(0.05, 10, 0.5), Eigen::Quaterniond::Identity()});
    struct Target {
        Eigen::Vector3d centreM;
        double frontRatio, netRatio;
    };
    for (const Target& target : {Target{{2.5, 0, 0.5}, 0.205, 0.09}, Target{{3.6, 0, 0.1}, 0.476, 0.376}}) {
        const std::vector<Body> block{test::boxBody(2, 2, 2, 0.1, 2000.0, target.centreM)};
        const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::Surface, 0.365, target.centreM.norm());
        const double dt = p.positiveDurationS / 200, until = p.arrivalTimeS + p.positiveDurationS + p.negativeDurationS;
        auto netImpulse = [&](const StaticWorld& geometry) {  // as the CFD's: the running integral's maximum
            double total = 0, largest = 0;
            for (double t = 0; t < until; t += dt) {
                const auto windows = field.openWindows(t);
                total += BlastLoads(field, windows, LoadSettings(), geometry).stepWrenches(block, {1}, t, dt)[0].forceN.x() * dt;
                largest = std::max(largest, total);
            }
            return largest;
        };
        auto front = [](const ExposedFace& f) { return f.face == kNegX; };
        const double positiveEnd = p.arrivalTimeS + p.positiveDurationS;
        const double frontRatio = faceImpulseOn(block[0], field, walled, dt, positiveEnd, front) /
                                  faceImpulseOn(block[0], field, open, dt, positiveEnd, front);
        const double netRatio = netImpulse(walled) / netImpulse(open);
        std::printf("target at x %.1f: front %.3f (CFD %.3f), net %.3f (CFD %.3f)\n", target.centreM.x(), frontRatio, target.frontRatio,
                    netRatio, target.netRatio);
        EXPECT_NEAR(frontRatio, target.frontRatio, 0.3 * target.frontRatio);
        EXPECT_NEAR(netRatio, target.netRatio, 0.3 * target.netRatio);
    }
}

TEST(Loads, DiffractedWaveBehindABarrierKeepsWhatTheCfdFinds)
{
    // shared/reference/blast-loads-cfd.md: at free points 0.3-2 m behind the 1 m barrier and
    // 0.1-1 m up, the side-on positive impulse is 0.43-0.65 of what it is without the barrier.
    // spall's diffracted wave keeps 0.35-0.94: close behind and low down it matches, but near
    // the line of sight over the top it loses almost nothing, where the CFD loses a third (the
    // ray model has no penumbra; docs/accuracy.md). Checked: the weakest point within 30 % of
    // the CFD's, every point weakened, and the wave travelling on over the top.
    const BlastField field({Charge{Eigen::Vector3d::Zero(), 0.365, 0.0, BurstType::Surface}}, BlastSettings());
    StaticWorld walled = test::groundAtZero();
    const ObstacleBox barrier{Eigen::Vector3d(2.05, 0, 0.5), Eigen::Vector3d(0.05, 10, 0.5), Eigen::Quaterniond::Identity()};
    auto sideOnImpulse = [](const PointPulse& p) {
        return p.peakOverpressurePa * p.positiveDurationS * friedlanderImpulseFraction(p.decayCoefficient);
    };
    // Over a long thin wall the path is straight up to the near top edge, across, and straight down.
    const Eigen::Vector3d behindIt(4.0, 0, 0.5);
    const EdgePath over = shortestPathAround(barrier, Eigen::Vector3d::Zero(), behindIt, walled, 0.01);
    EXPECT_NEAR(over.lengthM, Eigen::Vector3d(2.0, 0, 1.0).norm() + 0.1 + (behindIt - Eigen::Vector3d(2.1, 0, 1.0)).norm(), 1e-9);
    EXPECT_NEAR((over.leaveM - Eigen::Vector3d(2.1, 0, 1.0)).norm(), 0.0, 1e-9);
    double lowest = 1, highest = 0;
    for (double behind : {0.3, 0.7, 1.2, 2.0})
        for (double height : {0.1, 0.4, 0.7, 1.0}) {
            const Eigen::Vector3d point(2.1 + behind, 0, height);
            const EdgePath path = shortestPathAround(barrier, Eigen::Vector3d::Zero(), point, walled, 0.01);
            const DiffractedWave wave = diffractedWave(path, Eigen::Vector3d::Zero(), point);
            const double ratio = sideOnImpulse(field.pulseAt(0, wave.equivalentDistanceM * wave.equivalentDistanceM)) /
                                 sideOnImpulse(field.pulseAt(0, point.squaredNorm()));
            lowest = std::min(lowest, ratio), highest = std::max(highest, ratio);
            EXPECT_GT(wave.directionM.x(), 0.0);
            EXPECT_LE(wave.directionM.z(), 1e-12) << "the wave comes over the top";
        }
    std::printf("side-on impulse behind the barrier / without it: %.2f-%.2f (CFD 0.43-0.65)\n", lowest, highest);
    EXPECT_NEAR(lowest, 0.43, 0.3 * 0.43);
    EXPECT_LT(highest, 1.0);
}

TEST(Loads, GroundReflectsAFreeAirCharge)
{
    // A free-air charge above the ground gets the ground's reflection as an image charge.
    // Reference: just above the height where a charge counts as a surface burst, the wave on a
    // wall standing on the ground is Kingery–Bulmash's hemispherical surface burst; the linear
    // image sums two free-air waves where the real ones merge (docs/accuracy.md).
    const double tnt = 1.0, h = 0.1;
    const StaticWorld ground = test::groundAtZero();
    const Body wall = test::boxBody(1, 100, 20, h, 2000.0, Eigen::Vector3d(3.0 + 0.5 * h, 0, 1.0));
    auto strip = [](const ExposedFace& f) { return f.face == kNegX && f.voxel.y() >= 48 && f.voxel.y() <= 51 && f.voxel.z() < 5; };
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::Surface, tnt, 3.0);
    const double dt = p.positiveDurationS / 200, until = 2 * (p.arrivalTimeS + p.positiveDurationS);
    const double height = 1.05 * surfaceBurstHeightM(tnt);
    const Charge air{Eigen::Vector3d(0, 0, height), tnt, 0.0, BurstType::FreeAir};
    const double surface = faceImpulseOn(wall, BlastField({Charge{Eigen::Vector3d::Zero(), tnt, 0.0, BurstType::Surface}}, BlastSettings()),
                                         ground, dt, until, strip);
    const double imaged = faceImpulseOn(wall, BlastField(withGroundImages({air}, Eigen::Vector3d::UnitZ(), 0.0), BlastSettings()), ground, dt,
                                        until, strip);
    const double alone = faceImpulseOn(wall, BlastField({air}, BlastSettings()), ground, dt, until, strip);
    std::printf("wall strip 3 m from 1 kg at %.2f m: free air %.1f, with the ground's image %.1f, surface burst %.1f N s\n", height, alone,
                imaged, surface);
    EXPECT_GT(imaged, 1.5 * alone);
    EXPECT_NEAR(imaged, surface, 0.15 * surface);
}

TEST(Loads, AWindowInAWallOfCollidersIsLoadedAsThatPartOfASolidWall)
{
    // The air cannot tell a wall made of static colliders from one made of a body: a 0.6 m
    // pane held in the opening of a 4 m x 3 m wall of four colliders must take, on its front
    // and on its rear, the impulse the same 0.6 m patch of a solid wall of the same outline
    // takes (UFC 3-340-02 §2-15.3: clearing and the rear's rise follow the whole wall). Loaded
    // as a 0.6 m plate standing free, it cleared round its own edges and filled behind at once.
    const double h = 0.1, tnt = 1.0, distance = 6.0;
    const BlastField field({Charge{Eigen::Vector3d::Zero(), tnt, 0.0, BurstType::Surface}}, BlastSettings());
    const StaticWorld open = test::groundAtZero();
    const Body solid = test::boxBody(1, 40, 30, h, 2500.0, Eigen::Vector3d(distance + 0.5 * h, 0, 1.5));
    Body pane = test::boxBody(1, 6, 6, h, 2500.0, Eigen::Vector3d(distance + 0.5 * h, 0, 1.5));
    pane.anchored = true;
    StaticWorld walled = open;
    const double cx = distance + 0.5 * h, hx = 0.5 * h;
    walled.boxes = {{Eigen::Vector3d(cx, -1.15, 1.5), Eigen::Vector3d(hx, 0.85, 1.5), Eigen::Quaterniond::Identity()},
                        {Eigen::Vector3d(cx, 1.15, 1.5), Eigen::Vector3d(hx, 0.85, 1.5), Eigen::Quaterniond::Identity()},
                        {Eigen::Vector3d(cx, 0, 0.6), Eigen::Vector3d(hx, 0.3, 0.6), Eigen::Quaterniond::Identity()},
                        {Eigen::Vector3d(cx, 0, 2.4), Eigen::Vector3d(hx, 0.3, 0.6), Eigen::Quaterniond::Identity()}};
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::Surface, tnt, distance);
    const double dt = p.positiveDurationS / 200, until = p.arrivalTimeS + p.positiveDurationS + p.negativeDurationS;
    // The solid wall's patch: voxels 17..22 across and 12..17 up, its pane's place.
    auto patch = [](int face) {
        return [face](const ExposedFace& f) { return f.face == face && f.voxel.y() >= 17 && f.voxel.y() <= 22 && f.voxel.z() >= 12 && f.voxel.z() <= 17; };
    };
    auto all = [](int face) { return [face](const ExposedFace& f) { return f.face == face; }; };
    const double solidFront = faceImpulseOn(solid, field, open, dt, until, patch(kNegX)), solidRear = faceImpulseOn(solid, field, open, dt, until, patch(kPosX));
    const double paneFront = faceImpulseOn(pane, field, walled, dt, until, all(kNegX)), paneRear = faceImpulseOn(pane, field, walled, dt, until, all(kPosX));
    const double freeFront = faceImpulseOn(pane, field, open, dt, until, all(kNegX)), freeRear = faceImpulseOn(pane, field, open, dt, until, all(kPosX));
    std::printf("0.6 m patch of a 4 m x 3 m wall: front %.3f, rear %.3f N s; a pane in a wall of colliders %.3f, %.3f; standing free %.3f, %.3f\n",
                solidFront, solidRear, paneFront, paneRear, freeFront, freeRear);
    EXPECT_NEAR(paneFront, solidFront, 0.01 * solidFront);
    EXPECT_NEAR(paneRear, solidRear, 0.01 * std::abs(solidFront));
    EXPECT_GT(std::abs(freeFront - solidFront) + std::abs(freeRear - solidRear), 0.05 * solidFront) << "the outline matters here";
}

TEST(Loads, ABlockOnTheGroundIsPressedIntoItNotLifted)
{
    // No air under a face resting on the ground, and the ground's reflection does not wrap round
    // what stands on it: a block under an air burst is pushed down.
    const StaticWorld ground = test::groundAtZero();
    const Charge air{Eigen::Vector3d(0.5, 0, 1.5), 1.0, 0.0, BurstType::FreeAir};
    const BlastField field(withGroundImages({air}, Eigen::Vector3d::UnitZ(), 0.0), BlastSettings());
    const Body block = test::boxBody(4, 4, 4, 0.1, 2000.0, Eigen::Vector3d(0, 0, 0.2));
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 1.0, 1.5);
    const Wrench total = impulseOnHeldBody(block, field, LoadSettings(), ground, p.positiveDurationS / 200, 0.05);
    EXPECT_LT(total.forceN.z(), 0.0);
}

TEST(Loads, TheWaveGoesRoundANarrowObstacleAlongTheGround)
{
    // A post 0.2 m wide and 3 m high between a surface charge and a point on the ground behind
    // it: the shortest way is round its side at ground level, not over its top.
    const StaticWorld ground = test::groundAtZero();
    const ObstacleBox post{Eigen::Vector3d(2.0, 0, 1.5), Eigen::Vector3d(0.1, 0.1, 1.5), Eigen::Quaterniond::Identity()};
    const Eigen::Vector3d behind(4.0, 0, 0.05);
    const EdgePath path = shortestPathAround(post, Eigen::Vector3d::Zero(), behind, ground, 0.01);
    const double roundTheSide = Eigen::Vector3d(1.9, 0.1, 0).norm() + 0.2 + (behind - Eigen::Vector3d(2.1, 0.1, 0)).norm();
    EXPECT_NEAR(path.lengthM, roundTheSide, 0.01);
    EXPECT_LT(path.leaveM.z(), 0.1);
}

TEST(Loads, APanelTakesTheSameImpulseAtEveryVoxelSize)
{
    // Issue 47, item 8: a concrete panel 0.5 × 0.1 × 0.5 m at 1.5 kg of TNT from 0.1 to 0.4 m
    // makes fewer pieces at 1.25 cm than at 2.5 cm; what the blast gives it is not why. The
    // faces' impulse is a quadrature of the pressure over the face, so it must not depend on h.
    for (const double standoffM : {0.1, 0.2, 0.3, 0.4}) {
        const BlastField field({Charge{Eigen::Vector3d(0, -standoffM - 0.05, 0.25), 1.5, 0.0, BurstType::FreeAir}}, BlastSettings());
        const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::FreeAir, 1.5, standoffM);
        std::vector<double> impulseNs;
        for (const double h : {0.025, 0.0125}) {
            const int side = int(std::lround(0.5 / h)), thickness = int(std::lround(0.1 / h));
            const Body panel = test::boxBody(side, thickness, side, h, 2400.0, Eigen::Vector3d(0, 0, 0.25));
            const Wrench w = impulseOnHeldBody(panel, field, LoadSettings(), StaticWorld(), 2e-6, p.arrivalTimeS + 10 * p.positiveDurationS);
            impulseNs.push_back(w.forceN.y());
            EXPECT_LT(w.forceN.cwiseAbs().x() + w.forceN.cwiseAbs().z(), 1e-6 * w.forceN.y()) << "the panel is symmetric about the charge's line";
        }
        EXPECT_NEAR(impulseNs[1], impulseNs[0], 0.01 * impulseNs[0]) << "standoff " << standoffM << " m";
    }
}

TEST(StructureLoads, AWideWallsFaceNearestTheChargeTakesThePublishedReflectedImpulse)
{
    // 0.5 kg on the ground 3 m in front of a wall 20 m wide and 10 m tall: a surface burst is a
    // free-air charge of twice the mass (UFC 3-340-02 §2-13), and the wall is wide enough that
    // clearing (tc ~ 50 ms) takes nothing from a 2.6 ms pulse. Its face at the foot, straight in
    // front of the charge, takes Kingery–Bulmash's normally reflected impulse of 1 kg at 3 m,
    // 147.1 Pa s (ARBRL-TR-02555, as in LargeWallAtNormalIncidenceTakesTheKingeryBulmashReflectedImpulse).
    const Scene scene = parseScene(R"({
      "voxel_size_m": 0.5, "duration_s": 0.1,
      "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [20, 0.5, 10]},
                   "position_m": [0, 0.25, 5], "material": "concrete", "anchor": "ground"}],
      "charges": [{"position_m": [0, -3, 0], "tnt_kg": 0.5, "burst": "surface"}]})", "wide-wall", ".");
    const Simulation simulation(scene);
    const StructureLoadsReport report = structureLoads(simulation);
    ASSERT_EQ(report.objects.size(), 1u);
    const ObjectLoads& wall = report.objects[0];
    const FrontFace& front = wall.front;
    EXPECT_EQ(front.face, kNegY);
    EXPECT_EQ(front.faces, 40u * 20u);
    const FaceLoad& nearest = wall.faces[front.nearest];
    EXPECT_NEAR(nearest.centreM.x(), 0.0, 0.26);
    EXPECT_NEAR(nearest.centreM.z(), 0.25, 0.01);
    EXPECT_NEAR(front.distanceM, 3.0, 0.03);
    EXPECT_NEAR(nearest.impulsePaS, 147.1, 0.05 * 147.1);
    EXPECT_EQ(front.maxImpulsePaS, nearest.impulsePaS) << "the face nearest the charge takes the most";
    // A property of the sampling, not of the model: the largest mean over a substep lies within
    // 2 % of the pulse's own peak there, the normally reflected pressure at its range.
    EXPECT_NEAR(nearest.peakPressurePa, front.reflectedPressurePa, 0.02 * front.reflectedPressurePa);
    // The wave reaches the face when the blast data says it reaches 3 m, within a substep.
    const BlastParameters p = blastParameters(BlastDataset::KingeryBulmash, BurstType::Surface, 0.5, front.distanceM);
    EXPECT_NEAR(nearest.arrivalTimeS, p.arrivalTimeS, report.timeStepS / 10 + 1e-9);
    // Conservation: the net impulse is the faces' impulses times their areas, summed as vectors;
    // the wall is pushed away from the charge, and its sides' pushes cancel.
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const FaceLoad& f : wall.faces) sum -= f.normal * (f.impulsePaS + f.negativeImpulsePaS) * 0.25;
    EXPECT_LT((sum - wall.netImpulseNS).norm(), 1e-9 * sum.norm());
    EXPECT_GT(wall.netImpulseNS.y(), 0.0);
    EXPECT_LT(std::abs(wall.netImpulseNS.x()), 1e-6 * wall.netImpulseNS.y());
}
