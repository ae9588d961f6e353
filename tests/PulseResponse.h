// What the pressure–impulse tests share (test_wall_response.cpp, test_pane_response.cpp): a
// mode's closed-form answer to a triangular pulse and a sum of modes' peak, a lattice stepped
// under one, and the bond closest to failing.
#pragma once

#include <spall/lattice/Lattice.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace spall::test {

/// q(t) of a mode of angular frequency w driven from rest by f0 (1 − t/td), f0 = loadPerMass
/// (Duhamel's integral; Clough & Penzien, Dynamics of Structures, ch. 6): f0/w² (1 − cos wt +
/// sin wt/(w td) − t/td) while the pulse lasts, then free vibration from where it left the mode.
inline double triangularPulseModalDeflection(double w, double loadPerMass, double td, double t)
{
    const double scale = loadPerMass / (w * w);
    if (t <= td) return scale * (1.0 - std::cos(w * t) + std::sin(w * t) / (w * td) - t / td);
    const double qEnd = scale * (std::sin(w * td) / (w * td) - std::cos(w * td));
    const double vEnd = scale * (w * std::sin(w * td) + (std::cos(w * td) - 1.0) / td);
    return qEnd * std::cos(w * (t - td)) + vEnd / w * std::sin(w * (t - td));
}

/// A mode's part in a response: its angular frequency, its modal load per pascal (q̈ per Pa),
/// and what a unit of its deflection adds to the response.
struct ModalTerm {
    double angularFrequencyRadS, loadPerPaMS2, responsePerDeflection;
};

/// The largest |Σ response| of `modes` under a triangular pulse of peak 1 Pa falling to 0 at
/// durationS, over runS, on a grid of 40 points per period of the fastest mode.
inline double peakModalResponsePerPascal(const std::vector<ModalTerm>& modes, double durationS, double runS)
{
    double fastest = 0.0;
    for (const ModalTerm& mode : modes) fastest = std::max(fastest, mode.angularFrequencyRadS);
    const double dt = 2.0 * M_PI / fastest / 40.0;
    double peak = 0.0;
    for (double t = 0.0; t <= runS; t += dt) {
        double response = 0.0;
        for (const ModalTerm& mode : modes)
            response += mode.responsePerDeflection * triangularPulseModalDeflection(mode.angularFrequencyRadS, mode.loadPerPaMS2, durationS, t);
        peak = std::max(peak, std::abs(response));
    }
    return peak;
}

/// Steps a lattice for runS under a pressure on the faces of `loaded` particles (each face h²,
/// pushed along `direction`), rising at once to peakPa and falling linearly to nothing at
/// durationS. Each step takes exactly the pulse's impulse over it.
inline void stepUnderTriangularPulse(Lattice& lattice, const std::vector<size_t>& loaded, const Eigen::Vector3d& direction, double peakPa,
                                     double durationS, double runS)
{
    const auto impulsePerPa = [&](double t) {
        const double s = std::min(t, durationS);
        return s - s * s / (2.0 * durationS);
    };
    const double dt = lattice.stableTimeStepS(), faceAreaM2 = lattice.model().spacingM * lattice.model().spacingM;
    for (double t = 0.0; t < runS; t += dt) {
        const double meanPa = peakPa * (impulsePerPa(t + dt) - impulsePerPa(t)) / dt;
        for (const size_t p : loaded) lattice.externalForceN[p] = meanPa * faceAreaM2 * direction;
        lattice.step(dt);
    }
}

/// The bond that came closest to failing, with its failure index (1: the failure surface;
/// Lattice::equivalentStretchM), and whether any bond has begun to soften.
struct ClosestToFailing {
    size_t bond = 0;
    double peakFailureIndex = 0.0;
    bool damaged = false;
};
inline ClosestToFailing closestToFailing(const Lattice& lattice)
{
    ClosestToFailing c;
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        const LatticeBond& bond = lattice.model().bonds[b];
        const double u0 = lattice.state.bondHistory[b].strengthScale * lattice.model().stiffness.strength[bond.strengthClass].peakStretchM;
        const double index = lattice.state.bondHistory[b].maxEquivalentStretchM / u0;
        c.damaged = c.damaged || lattice.bondDamage(b) > 0.0;
        if (index > c.peakFailureIndex) c = {b, index, c.damaged};
    }
    return c;
}

}  // namespace spall::test
