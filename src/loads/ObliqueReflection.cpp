#include <spall/loads/ObliqueReflection.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace spall {

namespace {

constexpr double kGamma = 1.4;
constexpr double kPi = 3.14159265358979323846;

/// Flow deflection across an oblique shock of wave angle beta in a flow of Mach m (the
/// theta-beta-M relation) (unit: rad).
double deflection(double mach, double beta)
{
    const double m2s2 = mach * mach * std::sin(beta) * std::sin(beta);
    return std::atan(2.0 / std::tan(beta) * (m2s2 - 1.0) / (mach * mach * (kGamma + std::cos(2.0 * beta)) + 2.0));
}

/// Static pressure ratio across a shock whose normal Mach number is mn.
double shockPressureRatio(double mn) { return 1.0 + 2.0 * kGamma / (kGamma + 1.0) * (mn * mn - 1.0); }

/// The wave angle of greatest deflection for Mach m (golden-section search; the deflection is
/// unimodal in beta between the Mach angle and 90 degrees).
double waveAngleOfLargestDeflection(double mach)
{
    double lo = std::asin(1.0 / mach), hi = 0.5 * kPi;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int i = 0; i < 60; ++i) {
        const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
        (deflection(mach, a) < deflection(mach, b) ? lo : hi) = deflection(mach, a) < deflection(mach, b) ? a : b;
    }
    return 0.5 * (lo + hi);
}

}  // namespace

TwoShockReflection twoShockReflection(double pressureRatio, double incidenceRad)
{
    const double shockMach = std::sqrt(1.0 + (kGamma + 1.0) / (2.0 * kGamma) * (pressureRatio - 1.0));
    // In the frame of the point where the shock meets the wall, the gas ahead streams along
    // the wall at Mach Ms / sin(alpha) into a standing oblique shock at wave angle alpha.
    const double alpha = std::clamp(incidenceRad, 1e-4, 0.5 * kPi - 1e-9);
    const double m0 = shockMach / std::sin(alpha);
    const double theta = deflection(m0, alpha);
    const double normal1 = std::sqrt((1.0 + 0.5 * (kGamma - 1.0) * shockMach * shockMach) /
                                     (kGamma * shockMach * shockMach - 0.5 * (kGamma - 1.0)));
    const double m1 = normal1 / std::sin(alpha - theta);
    TwoShockReflection out;
    if (m1 <= 1.0) return out;
    // The reflected shock turns the flow back parallel to the wall: the weak solution.
    double lo = std::asin(1.0 / m1), hi = waveAngleOfLargestDeflection(m1);
    if (deflection(m1, hi) < theta) return out;
    for (int i = 0; i < 50; ++i) {
        const double mid = 0.5 * (lo + hi);
        (deflection(m1, mid) < theta ? lo : hi) = mid;
    }
    out.regular = true;
    out.pressureRatio = pressureRatio * shockPressureRatio(m1 * std::sin(0.5 * (lo + hi)));
    return out;
}

double detachmentAngleRad(double pressureRatio)
{
    double lo = 1e-4, hi = 0.5 * kPi - 1e-9;
    if (twoShockReflection(pressureRatio, hi).regular) return hi;
    for (int i = 0; i < 40; ++i) {
        const double mid = 0.5 * (lo + hi);
        (twoShockReflection(pressureRatio, mid).regular ? lo : hi) = mid;
    }
    return lo;
}

namespace {

constexpr int kStrengths = 61;                 ///< Ps/p0 from 1e-3 to 1e3, ten per decade
constexpr double kLowestLog10 = -3.0, kLog10Step = 0.1;
constexpr int kAngles = 91;                    ///< alpha from 0 to 90 degrees, one per degree

using FractionTable = std::array<std::array<double, kAngles>, kStrengths>;

FractionTable buildTable()
{
    FractionTable table{};
    for (int s = 0; s < kStrengths; ++s) {
        const double xi = 1.0 + std::pow(10.0, kLowestLog10 + kLog10Step * s);
        const double headOn = twoShockReflection(xi, 1e-4).pressureRatio - xi;
        const double detachment = detachmentAngleRad(xi);
        const double atDetachment = twoShockReflection(xi, detachment).pressureRatio - xi;
        for (int a = 0; a < kAngles; ++a) {
            const double alpha = a * kPi / 180.0;
            const TwoShockReflection r = twoShockReflection(xi, alpha);
            const double excess = r.regular && alpha <= detachment
                                      ? r.pressureRatio - xi
                                      : atDetachment * std::pow(std::cos(alpha) / std::cos(detachment), 2);
            table[s][a] = excess / headOn;
        }
    }
    return table;
}

}  // namespace

double reflectedExcessFraction(double sideOnPa, double ambientPa, double cosIncidence)
{
    if (!(cosIncidence > 0.0) || !(sideOnPa > 0.0)) return 0.0;
    static const FractionTable table = buildTable();
    const double s = std::clamp((std::log10(sideOnPa / ambientPa) - kLowestLog10) / kLog10Step, 0.0, kStrengths - 1.0);
    const double a = std::clamp(std::acos(std::min(cosIncidence, 1.0)) * 180.0 / kPi, 0.0, kAngles - 1.0);
    const int s0 = std::min(int(s), kStrengths - 2), a0 = std::min(int(a), kAngles - 2);
    const double fs = s - s0, fa = a - a0;
    return (1 - fs) * ((1 - fa) * table[s0][a0] + fa * table[s0][a0 + 1]) + fs * ((1 - fa) * table[s0 + 1][a0] + fa * table[s0 + 1][a0 + 1]);
}

}  // namespace spall
