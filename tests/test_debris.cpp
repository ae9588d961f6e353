#include <spall/analysis/Debris.h>
#include <spall/core/Error.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace spall;

namespace {

constexpr double kG = 9.80665;

/// A history built frame by frame: each frame a list of bodies.
struct HistoryBuilder {
    History h;
    explicit HistoryBuilder(const Eigen::Vector3d& charge = Eigen::Vector3d::Zero())
    {
        h.bodyOffset.push_back(0);
        h.chargePositionM.push_back(charge);
        h.chargeTntKg.push_back(1.0);
    }
    void body(int64_t id, int64_t parent, double massKg, const Eigen::Vector3d& x, const Eigen::Vector3d& v, bool anchored = false)
    {
        h.bodyId.push_back(id);
        h.bodyParentId.push_back(parent);
        h.bodyMassKg.push_back(massKg);
        h.bodyPositionM.push_back(x);
        h.bodyLinearVelocityMS.push_back(v);
        h.bodyAnchored.push_back(anchored);
    }
    void endFrame(double timeS)
    {
        h.timeS.push_back(timeS);
        h.bodyOffset.push_back(static_cast<int64_t>(h.bodyId.size()));
    }
};

const FragmentFlight& fragment(const DebrisReport& r, int64_t id)
{
    for (const FragmentFlight& f : r.fragments)
        if (f.id == id) return f;
    throw std::runtime_error("no fragment " + std::to_string(id));
}

}  // namespace

TEST(Debris, AFragmentThrownAndSplitInFlightIsFollowedThroughItsParentToItsImpact)
{
    // A 10 kg block rests until frame 3, leaves (2, 0, 1) at (10, 0, 5) m/s in vacuum, splits into
    // 4 and 6 kg halves at frame 10 and lands at z = 0, where the halves stop.
    const double fps = 24, m = 10;
    const Eigen::Vector3d x0(2, 0, 1), v0(10, 0, 5), g(0, 0, -kG);
    const double tLaunch = 3 / fps, tFlight = (v0.z() + std::sqrt(v0.z() * v0.z() + 2 * kG * x0.z())) / kG;
    HistoryBuilder b;
    int lastInFlight = -1;
    for (int f = 0; f < 48; ++f) {
        const double t = f / fps, s = t - tLaunch;
        Eigen::Vector3d x = x0, v = Eigen::Vector3d::Zero();
        if (s >= 0 && s < tFlight) {
            x = x0 + v0 * s + 0.5 * g * s * s;
            v = v0 + g * s;
            lastInFlight = f;
        } else if (s >= tFlight) {
            x = x0 + v0 * tFlight + 0.5 * g * tFlight * tFlight;
        }
        if (f < 10) {
            b.body(1, -1, m, x, v);
        } else {
            b.body(2, 1, 4, x, v);
            b.body(3, 1, 6, x, v);
        }
        b.endFrame(t);
    }
    const DebrisReport r = analyseDebris(b.h);
    ASSERT_EQ(r.fragments.size(), 2u);
    const Eigen::Vector3d vBefore = v0 + g * (lastInFlight / fps - tLaunch);
    const Eigen::Vector3d landing = x0 + v0 * tFlight + 0.5 * g * tFlight * tFlight;
    for (int64_t id : {2, 3}) {
        const FragmentFlight& f = fragment(r, id);
        const double mass = id == 2 ? 4 : 6;
        EXPECT_TRUE(f.launched);
        EXPECT_NEAR(f.launchTimeS, tLaunch, 1e-12);
        EXPECT_NEAR((f.launchVelocityMS - v0).norm(), 0, 1e-12);
        ASSERT_TRUE(f.impacted);
        EXPECT_NEAR(f.impactTimeS, (lastInFlight + 1) / fps, 1e-12);
        EXPECT_NEAR(f.impactKineticEnergyJ, 0.5 * mass * vBefore.squaredNorm(), 1e-9);
        EXPECT_NEAR(f.peakKineticEnergyJ, 0.5 * mass * vBefore.squaredNorm(), 1e-9) << "fastest just before it lands, below its start";
        EXPECT_NEAR(f.throwDistanceM, landing.x(), 1e-12);
        EXPECT_TRUE(f.hazardous) << f.impactKineticEnergyJ << " J";
    }
}

TEST(Debris, HazardousFragmentDistanceFollowsTheDensityLimitOverRingsAndSectors)
{
    // 30 hazardous pieces land 1.0-1.9 m out along +x, one at 30.5 m; 1 m rings, 8 sectors.
    // Ring 1-2 m: 30 / (pi (4 - 1)) = 3.2 per m^2, over the limit 1/55.7. Ring 30-31 m: 1 /
    // (pi (961 - 900)) = 1/191.6 under it over the whole ring, but 1/23.95 in its sector, over it.
    HistoryBuilder b;
    const Eigen::Vector3d falling(0, 0, -20), stopped = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> at;
    for (int i = 0; i < 30; ++i) at.push_back(Eigen::Vector3d(1.0 + 0.03 * i, 0.01 * (i % 3), 0));
    at.push_back(Eigen::Vector3d(30.5, 1.0, 0));
    at.push_back(Eigen::Vector3d(-5.5, 0, 0));  // and a slow one that is not hazardous
    for (int frame = 0; frame < 2; ++frame) {
        for (size_t i = 0; i < at.size(); ++i) {
            const Eigen::Vector3d v = i + 1 == at.size() ? Eigen::Vector3d(0, 0, -1) : falling;
            // Each falls from 2 m above the charge onto its spot.
            b.body(static_cast<int64_t>(i), -1, 1.0, frame == 0 ? Eigen::Vector3d(0, 0, 2) : at[i], frame == 0 ? v : stopped);
        }
        b.endFrame(frame / 24.0);
    }
    DebrisSettings s;
    s.ringWidthM = 1.0;
    const DebrisReport r = analyseDebris(b.h, s);
    EXPECT_EQ(r.hazardousCount(), 31);  // 1/2 20^2 = 200 J each; the slow one 0.5 J
    ASSERT_EQ(r.rings.size(), 31u);
    EXPECT_EQ(r.rings[1].hazardous, 30);
    EXPECT_NEAR(r.rings[1].hazardousDensityPerM2(), 30 / (M_PI * 3), 1e-12);
    EXPECT_EQ(r.rings[5].fragments, 1);
    EXPECT_EQ(r.rings[30].sectorHazardous[0], 1);
    EXPECT_NEAR(r.hazardousFragmentDistanceM, 2.0, 1e-12);
    EXPECT_NEAR(r.worstSectorHazardousFragmentDistanceM, 31.0, 1e-12);
    EXPECT_NEAR(r.maxThrowDistanceM, std::hypot(30.5, 1.0), 1e-12);
    EXPECT_NEAR(r.medianThrowDistanceM, at[15].head<2>().norm(), 1e-12) << "the 16th nearest of 32";
}

TEST(Debris, WeibullFitRecoversTheLawOfMassesAtItsQuantiles)
{
    // Masses at the exact plotting positions of N(>m) = N exp(-(m/0.7 kg)^0.5), Mott's law.
    HistoryBuilder b;
    const int n = 200;
    for (int frame = 0; frame < 2; ++frame) {
        for (int i = 0; i < n; ++i) {
            const double m = 0.7 * std::pow(-std::log((i + 0.5) / n), 1 / 0.5);
            b.body(i, -1, m, Eigen::Vector3d(frame == 0 ? 0 : 3, 0, 0), Eigen::Vector3d::Zero());
        }
        b.endFrame(frame);
    }
    const DebrisReport r = analyseDebris(b.h);
    EXPECT_EQ(r.massFit.fragments, n);
    EXPECT_NEAR(r.massFit.shape, 0.5, 1e-9);
    EXPECT_NEAR(r.massFit.scaleKg, 0.7, 1e-9);
    EXPECT_NEAR(r.massFit.rSquared, 1.0, 1e-12);
}

TEST(Debris, WhatStaysWhereItStoodIsNotDebrisAndAHistoryWithoutChargesIsRefused)
{
    // An anchored stump, a piece that broke off it but stands 5 cm from where it came to be, and a
    // piece thrown from 4.5 m to 9 m.
    HistoryBuilder b;
    for (int frame = 0; frame < 2; ++frame) {
        b.body(1, -1, 500, Eigen::Vector3d(4, 0, 0.5), Eigen::Vector3d::Zero(), true);
        b.body(2, 1, 40, Eigen::Vector3d(4.5 + 0.05 * frame, 0, 0.5), Eigen::Vector3d::Zero());
        b.body(3, 1, 3, frame == 0 ? Eigen::Vector3d(4.5, 0, 1) : Eigen::Vector3d(9, 0, 0), Eigen::Vector3d::Zero());
        b.endFrame(frame / 24.0);
    }
    const DebrisReport r = analyseDebris(b.h);
    EXPECT_EQ(r.debrisCount(), 1);
    EXPECT_TRUE(fragment(r, 1).stayed);
    EXPECT_TRUE(fragment(r, 2).stayed);
    EXPECT_FALSE(fragment(r, 3).stayed);
    EXPECT_NEAR(r.maxThrowDistanceM, 9.0, 1e-12);
    b.h.chargeTntKg.clear();
    b.h.chargePositionM.clear();
    EXPECT_THROW(analyseDebris(b.h), InputError);
}
