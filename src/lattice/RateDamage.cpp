// Davison–Stevens's B and C fitted to a strain-rate law (lattice/RateDamage.h).
#include <spall/lattice/RateDamage.h>

#include <algorithm>
#include <cmath>

namespace spall {

double davisonStevensPeakFactor(const DavisonStevensConstants& law, double strainRatePerS)
{
    // In strain ε/ε0 = e as the clock: dD/de = (B ε0 / ε̇) [exp(c x) − 1], x = (1 − D) e − 1. Each
    // step moves c x by at most 0.02 and D by at most 0.001 (first order; the law is a rate, the
    // stiffness of its exponential is what limits the step).
    const double c = law.excessExponent, perStrain = law.rateTimesPeakStrainPerS / strainRatePerS;
    double damage = 0.0, strain = 1.0, peak = 1.0;
    for (;;) {
        const double excess = (1.0 - damage) * strain - 1.0;
        // Past exp(300) the bond has broken within the step anyway.
        const double rate = excess > 0.0 ? perStrain * std::expm1(std::min(c * excess, 300.0)) : 0.0;
        const double excessRate = std::abs((1.0 - damage) - strain * rate);
        const double step = std::min({1e-2, 0.02 / (c * excessRate + 1e-12), rate > 0.0 ? 1e-3 / rate : 1.0});
        damage = std::min(1.0, damage + rate * step);
        strain += step;
        const double stress = (1.0 - damage) * strain;
        if (stress > peak) peak = stress;
        // Past the peak the stress falls steeply; far beyond any DIF measured the law has no rate effect left to show.
        else if (stress < 0.9 * peak || damage >= 1.0 || strain > 20.0) return peak;
    }
}

namespace {

/// B ε0 such that the bond peaks at `factor` at `ratePerS` for this C ft: the peak falls as B grows.
double rateTimesPeakStrainFor(double excessExponent, double ratePerS, double factor)
{
    double logLow = -60.0, logHigh = 60.0;
    for (int i = 0; i < 40; ++i) {
        const double mid = 0.5 * (logLow + logHigh);
        if (davisonStevensPeakFactor({excessExponent, std::exp(mid)}, ratePerS) > factor) logLow = mid;
        else logHigh = mid;
    }
    return std::exp(0.5 * (logLow + logHigh));
}

DavisonStevensConstants fit(StrengthRateLaw rateLaw)
{
    const double slowFactor = dynamicIncreaseFactor(rateLaw, kDavisonStevensSlowFitRatePerS);
    const double fastFactor = dynamicIncreaseFactor(rateLaw, kDavisonStevensFastFitRatePerS);
    // With the slow rate matched, a steeper exponential (larger C ft) makes the peak grow more
    // slowly with rate (about as ln(ε̇) / (C ft)).
    double logLow = 0.0, logHigh = std::log(1000.0);
    for (int i = 0; i < 30; ++i) {
        const double mid = 0.5 * (logLow + logHigh);
        const double b = rateTimesPeakStrainFor(std::exp(mid), kDavisonStevensSlowFitRatePerS, slowFactor);
        if (davisonStevensPeakFactor({std::exp(mid), b}, kDavisonStevensFastFitRatePerS) > fastFactor) logLow = mid;
        else logHigh = mid;
    }
    const double c = std::exp(0.5 * (logLow + logHigh));
    return {c, rateTimesPeakStrainFor(c, kDavisonStevensSlowFitRatePerS, slowFactor)};
}

}  // namespace

DavisonStevensConstants davisonStevensFitTo(StrengthRateLaw law)
{
    switch (law) {
    case StrengthRateLaw::None:
        return {};
    case StrengthRateLaw::FibModelCode2010: {
        static const DavisonStevensConstants fitted = fit(law);
        return fitted;
    }
    }
    return {};
}

}  // namespace spall
