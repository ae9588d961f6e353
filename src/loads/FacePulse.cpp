#include <spall/loads/FacePulse.h>

#include <spall/loads/ObliqueReflection.h>

#include <algorithm>
#include <cmath>

namespace spall {

namespace {

/// A Gauss–Legendre rule on [-1, 1] (Abramowitz & Stegun 1964, table 25.4): n points integrate
/// polynomials of degree 2n − 1 exactly.
struct GaussRule {
    const double* nodes;
    const double* weights;
    size_t count;
};
constexpr double kNodes2[] = {-0.5773502691896258, 0.5773502691896258}, kWeights2[] = {1.0, 1.0};
constexpr double kNodes3[] = {-0.7745966692414834, 0.0, 0.7745966692414834},
                 kWeights3[] = {0.5555555555555556, 0.8888888888888889, 0.5555555555555556};
constexpr double kNodes5[] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
constexpr double kWeights5[] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665, 0.2369268850561891};
constexpr GaussRule kTwoPoints{kNodes2, kWeights2, 2}, kThreePoints{kNodes3, kWeights3, 3}, kFivePoints{kNodes5, kWeights5, 5};

/// The fewest points that integrate e^(−t/τ) over a part of length ℓ to a relative error of
/// about 1e-10: the n-point rule's error is (n!)⁴ / ((2n + 1) ((2n)!)³) (ℓ/τ)^(2n) (Abramowitz
/// & Stegun 25.4.30), 2.3e-4 (ℓ/τ)⁴ for two points and 5.0e-7 (ℓ/τ)⁶ for three. τ here is half
/// the fastest decay length, as the dynamic pressure decays as the square of the side-on one.
/// A lattice's steps (microseconds against a pulse's milliseconds) take two or three points.
GaussRule ruleForPart(double partOverHalfDecay)
{
    if (partOverHalfDecay <= 1.0 / 32.0) return kTwoPoints;
    if (partOverHalfDecay <= 1.0 / 4.0) return kThreePoints;
    return kFivePoints;
}

/// Positive-phase pressure on the face, 0 <= tau <= T+.
double positivePhasePa(const PointPulse& pulse, const FaceExposure& face, double tau, double ambientPa)
{
    const double ps = friedlanderOverpressure(pulse.peakOverpressurePa, pulse.positiveDurationS, pulse.decayCoefficient, tau);
    const double c = face.cosIncidence;
    const double stagnation = ps + dragCoefficient(c) * dynamicPressurePa(ps, ambientPa);
    double reflected = ps;
    if (c > 0.0) {
        const double pr = friedlanderOverpressure(pulse.reflectedPeakPa, pulse.positiveDurationS, pulse.reflectedDecayCoefficient, tau);
        reflected = ps + (pr - ps) * face.reflectedFraction;
    }
    // UFC 3-340-02 §2-15.3: the reflected pressure falls linearly to the stagnation pressure
    // at the clearing time, and follows it from then on.
    const double uncleared = std::max(0.0, 1.0 - tau / face.clearingTimeS);
    const double riseS = c < 0.0 ? -c * face.rearRiseTimeS : 0.0;
    const double rise = tau < riseS ? tau / riseS : 1.0;
    return rise * (stagnation + uncleared * (reflected - stagnation));
}

/// Integral of f over [a, b] by a Gauss–Legendre rule on n equal parts.
template <typename F>
double gaussLegendre(F&& f, double a, double b, int n, const GaussRule& rule)
{
    const double width = (b - a) / n;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
        const double mid = a + (k + 0.5) * width;
        for (size_t i = 0; i < rule.count; ++i) sum += rule.weights[i] * f(mid + 0.5 * width * rule.nodes[i]);
    }
    return 0.5 * width * sum;
}

}  // namespace

FaceExposure faceExposure(const PointPulse& pulse, double cosIncidence, double clearingTimeS, double rearRiseTimeS, double ambientPa)
{
    return {cosIncidence, clearingTimeS, rearRiseTimeS, reflectedExcessFraction(pulse.peakOverpressurePa, ambientPa, cosIncidence)};
}

double dragCoefficient(double cosIncidence)
{
    const double c2 = cosIncidence * cosIncidence;
    return cosIncidence > 0.0 ? -0.4 + 1.4 * c2 : -0.4 + 0.15 * c2;
}

double faceOverpressurePa(const PointPulse& pulse, const FaceExposure& face, double sinceArrivalS, double ambientPa)
{
    if (sinceArrivalS < 0.0) return 0.0;
    if (sinceArrivalS <= pulse.positiveDurationS) return positivePhasePa(pulse, face, sinceArrivalS, ambientPa);
    const double tau = sinceArrivalS - pulse.positiveDurationS;
    if (tau < pulse.negativeDurationS) return negativePhaseOverpressure(pulse.negativePeakPa, pulse.negativeDurationS, tau);
    return 0.0;
}

double faceImpulsePaS(const PointPulse& pulse, const FaceExposure& face, double fromS, double toS, double ambientPa)
{
    const double positiveEnd = pulse.positiveDurationS;
    const double negativeEnd = positiveEnd + pulse.negativeDurationS;
    // Smooth pieces: split at the end of clearing and of the rise, and at each phase's end.
    const double riseEnd = face.cosIncidence < 0.0 ? -face.cosIncidence * face.rearRiseTimeS : 0.0;
    double breaks[] = {0.0, std::min(face.clearingTimeS, positiveEnd), std::min(riseEnd, positiveEnd), positiveEnd, negativeEnd};
    std::sort(std::begin(breaks), std::end(breaks));
    // Each piece in parts of at most a quarter of the fastest decay length in the positive phase
    // (the negative phase's length in it), each part by the fewest points that keep it exact to
    // about 1e-10 (ruleForPart).
    const double fastestDecay = std::max({1.0, std::abs(pulse.decayCoefficient), std::abs(pulse.reflectedDecayCoefficient)});
    double impulse = 0.0;
    for (size_t piece = 0; piece + 1 < std::size(breaks); ++piece) {
        const double a = std::max(fromS, breaks[piece]), b = std::min(toS, breaks[piece + 1]);
        if (!(b > a)) continue;
        const double scale = b <= positiveEnd ? positiveEnd / fastestDecay : pulse.negativeDurationS;
        const int parts = std::clamp(static_cast<int>(std::ceil(4.0 * (b - a) / scale)), 1, 256);
        const GaussRule rule = ruleForPart(2.0 * (b - a) / (parts * scale));
        impulse += gaussLegendre([&](double tau) { return faceOverpressurePa(pulse, face, tau, ambientPa); }, a, b, parts, rule);
    }
    return impulse;
}

}  // namespace spall
