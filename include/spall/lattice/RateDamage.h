// Davison–Stevens damage on a lattice bond's stress (lattice.damage_law "davison-stevens"),
// calibrated to the material's strain-rate law: dD/dt = B [exp(C σx) − 1], σx the bond's stress
// beyond what its softening line allows (Lattice::rateDamageAfter; the paper's eq. 2.2 and 3.2).
#pragma once

#include <spall/fracture/Material.h>

namespace spall {

/// B and C in a form that holds for every strength and stiffness: with σ measured in units of
/// the tensile strength ft and strain in units of the peak strain ε0 = ft / E, a bond's damage
/// rate is B [exp(C ft σx/ft) − 1], so C ft and B ε0 are the law.
struct DavisonStevensConstants {
    /// C ft: how steeply the damage rate grows with the stress in excess, per ft (unit: 1).
    double excessExponent = 0.0;
    /// B ε0: B is this over the bond's peak strain (unit: 1/s).
    double rateTimesPeakStrainPerS = 0.0;
};

/// The peak stress, over ft, of a bond strained at a constant rate from rest under the law: the
/// maximum of (1 − D) ε/ε0 with dD/dt = B [exp(C ft ((1 − D) ε/ε0 − 1)) − 1] once (1 − D) ε > ε0.
/// Before the softening line has fallen far (its strain span 2 Gf / (ft h) is large against the
/// overstress's ε0 (DIF − 1)), this is what the lattice's bonds peak at (unit: 1).
double davisonStevensPeakFactor(const DavisonStevensConstants& law, double strainRatePerS);

/// The strain rates the law is fitted at: MC2010's lower branch (eq. 5.1-108), where the
/// material's own rate sensitivity governs; its steep branch above 10 1/s is in good part the
/// inertia of the specimens tested, which the lattice carries by itself (unit: 1/s).
inline constexpr double kDavisonStevensSlowFitRatePerS = 1e-3;
inline constexpr double kDavisonStevensFastFitRatePerS = 10.0;

/// B and C such that a bond of peak strain ε0 pulled at the two fit rates peaks at the rate law's
/// dynamic increase factors there (bisection on C ft, and on B ε0 for each). Computed once per
/// law. A law of None has no rate effect to fit: zero constants.
DavisonStevensConstants davisonStevensFitTo(StrengthRateLaw law);

}  // namespace spall
