// A face's pulse against exact references: its step impulses against a very fine quadrature of
// the whole pulse, reflection against the angle of incidence, and two-shock theory's oblique
// reflection against its limits.
#include <spall/loads/FacePulse.h>
#include <spall/loads/ObliqueReflection.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace spall;

namespace {

/// A pulse with round numbers (not from any table) for the quadrature checks.
PointPulse roundPulse()
{
    PointPulse p;
    p.arrivalTimeS = 0.0;
    p.positiveDurationS = 2e-3;
    p.peakOverpressurePa = 150e3;
    p.decayCoefficient = 1.5;
    p.reflectedPeakPa = 480e3;
    p.reflectedDecayCoefficient = 3.0;
    p.negativePeakPa = 10e3;
    p.negativeDurationS = 15e-3;
    p.shockSpeedMS = 500.0;
    return p;
}

/// Trapezoid rule on a very fine grid with the pulse's kinks as grid points.
double fineImpulse(const PointPulse& p, const FaceExposure& face, double from, double to, int n = 2'000'000)
{
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        const double a = from + (to - from) * i / n, b = from + (to - from) * (i + 1) / n;
        sum += 0.5 * (faceOverpressurePa(p, face, a, 101325) + faceOverpressurePa(p, face, b, 101325)) * (b - a);
    }
    return sum;
}

}  // namespace

TEST(FacePulse, StepImpulsesAddUpToTheWholePulse)
{
    // Exact integration per step: any split of time into steps gives the same total, equal to a
    // brute-force integral of the pressure history.
    const PointPulse p = roundPulse();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> step(1e-6, 4e-4);
    for (const FaceExposure face : {FaceExposure{1.0, 0.6e-3, 0.0}, FaceExposure{0.5, 1e30, 0.0}, FaceExposure{-1.0, 0.5e-3, 1e-3},
                                    FaceExposure{-0.3, 0.5e-3, 1e-3}, FaceExposure{0.0, 1e30, 0.0}}) {
        const double end = p.positiveDurationS + p.negativeDurationS + 1e-3;
        double sum = 0;
        for (double t = -1e-3; t < end;) {
            const double dt = std::min(step(rng), end - t);
            sum += faceImpulsePaS(p, face, t, t + dt, 101325);
            t += dt;
        }
        const double reference = fineImpulse(p, face, 0.0, end);
        EXPECT_NEAR(sum, reference, 1e-6 * std::abs(reference) + 1e-9) << "cos " << face.cosIncidence;
    }
}

TEST(FacePulse, EachShortStepIsIntegratedToNineDigits)
{
    // A lattice's steps are microseconds against a pulse's milliseconds, and take the fewest
    // Gauss points: each step's impulse against a trapezoid rule of 20 000 parts between the
    // pulse's kinks (its error, (dt/τ)² / 12n², under 1e-12 here), in the positive phase and
    // across arrival, clearing, the rise and the phase's end.
    const PointPulse p = roundPulse();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> step(1e-6, 1e-4), start(-1e-4, 4e-3);
    double worst = 0.0;
    for (const FaceExposure face : {FaceExposure{1.0, 0.6e-3, 0.0}, FaceExposure{0.5, 1e30, 0.0}, FaceExposure{-1.0, 0.5e-3, 1e-3},
                                    FaceExposure{-0.3, 0.5e-3, 1e-3}}) {
        const double kinks[] = {0.0, face.clearingTimeS, std::max(0.0, -face.cosIncidence) * face.rearRiseTimeS, p.positiveDurationS};
        for (int i = 0; i < 60; ++i) {
            const double from = start(rng), to = from + step(rng);
            std::vector<double> ends = {from, to};
            for (const double kink : kinks)
                if (kink > from && kink < to) ends.push_back(kink);
            std::sort(ends.begin(), ends.end());
            double reference = 0.0;
            for (size_t k = 0; k + 1 < ends.size(); ++k)
                if (ends[k] >= 0.0) reference += fineImpulse(p, face, ends[k], ends[k + 1], 20'000);
            const double got = faceImpulsePaS(p, face, from, to, 101325);
            const double error = std::abs(got - reference) / (std::abs(reference) + 1e-12 * p.reflectedPeakPa * (to - from));
            worst = std::max(worst, error);
            EXPECT_LT(error, 1e-9) << "cos " << face.cosIncidence << " from " << from << " s to " << to << " s";
        }
    }
    std::printf("short steps: largest relative error %.2e\n", worst);
}

TEST(FacePulse, ReflectionFollowsTheAngleOfIncidence)
{
    const PointPulse p = roundPulse();
    const double p0 = 101325, tc = 0.4e-3;
    // At arrival: the reflected peak head-on, side-on at grazing incidence from either side.
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, 1.0, tc, 0.0, p0), 0.0, p0), p.reflectedPeakPa, 1e-6);
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, 1e-9, tc, 0.0, p0), 0.0, p0), p.peakOverpressurePa, 1e-3);
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, -1e-9, tc, 1e-3, p0), 1e-12, p0), p.peakOverpressurePa, 1.0);
    // Never below side-on on the front.
    for (double c = 0.0; c <= 1.0; c += 0.05)
        EXPECT_GE(faceOverpressurePa(p, faceExposure(p, c, tc, 0.0, p0), 0.0, p0), p.peakOverpressurePa - 1e-6);
    // Cleared: the stagnation pressure, side-on plus Cd q (UFC: +1 front, -0.4 side, -0.25 rear).
    const double tau = 0.5e-3;
    const double ps = friedlanderOverpressure(p.peakOverpressurePa, p.positiveDurationS, p.decayCoefficient, tau);
    const double q = dynamicPressurePa(ps, p0);
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, 1.0, tc, 0.0, p0), tau, p0), ps + q, 1e-6);
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, 0.0, tc, 0.0, p0), tau, p0), ps - 0.4 * q, 1e-6);
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, -1.0, tc, 0.0, p0), tau, p0), ps - 0.25 * q, 1e-6);
    // A rear face builds up over its rise time.
    EXPECT_NEAR(faceOverpressurePa(p, faceExposure(p, -1.0, tc, 1e-3, p0), tau, p0), 0.5 * (ps - 0.25 * q), 1e-6);
}

TEST(ObliqueReflection, TwoShockTheoryMeetsItsLimits)
{
    const double p0 = 101325;
    for (double ps : {10e3, 100e3, 1e6}) {
        // Nearly head-on it is the normal reflection of Rankine–Hugoniot, Pr = 2 Ps (7 p0 + 4 Ps) / (7 p0 + Ps).
        const double normal = 2 * ps * (7 * p0 + 4 * ps) / (7 * p0 + ps);
        const TwoShockReflection r = twoShockReflection(1 + ps / p0, 0.01);
        ASSERT_TRUE(r.regular);
        EXPECT_NEAR((r.pressureRatio - 1) * p0, normal, 1e-3 * normal);
    }
    // Weak shocks at nearly glancing incidence: regular reflection ends where the glancing angle
    // is 2 sqrt(M^2 - 1) (the detachment value a_d = sqrt(2) of the transonic small-disturbance
    // scaling, Hunter and Brio 2000, J. Fluid Mech. 410:235), to O(angle^2).
    for (double ps : {30.0, 100.0, 300.0}) {
        const double xi = 1 + ps / p0, machSquared = 1 + 2.4 / 2.8 * (xi - 1);
        const double glancing = 2 * std::sqrt(machSquared - 1);
        EXPECT_NEAR(M_PI / 2 - detachmentAngleRad(xi), glancing, 0.02 * glancing) << ps << " Pa";
    }
    // The fraction of the reflected excess: 1 head-on, 0 at grazing incidence, and for shocks
    // up to about a bar at its largest, above head-on, at the transition to Mach reflection
    // (the pattern of UFC 3-340-02 Fig. 2-193; in the ideal gas stronger shocks have no peak).
    for (double ps : {10e3, 30e3, 100e3}) {
        EXPECT_NEAR(reflectedExcessFraction(ps, p0, 1.0), 1.0, 1e-9);
        EXPECT_NEAR(reflectedExcessFraction(ps, p0, 1e-6), 0.0, 1e-3);
        double largest = 0, atDegrees = 0;
        for (double degrees = 0; degrees <= 90; degrees += 0.25) {
            const double f = reflectedExcessFraction(ps, p0, std::cos(degrees * M_PI / 180));
            if (f > largest) largest = f, atDegrees = degrees;
        }
        EXPECT_GT(largest, 1.0);
        EXPECT_NEAR(atDegrees, detachmentAngleRad(1 + ps / p0) * 180 / M_PI, 2.5) << ps << " Pa";  // the table: 1 degree, 10 per decade
    }
}
