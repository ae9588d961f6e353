// The pressure history on one face from one charge, as blast engineering computes it (UFC 3-340-02,
// "Structures to Resist the Effects of Accidental Explosions", ch. 2): a face that looks at the
// charge sees the reflected pulse, relaxing to the stagnation pressure over the clearing time; a
// face that looks away sees the side-on pulse plus a drag term; every face sees the negative phase.
#pragma once

#include <spall/blast/Blast.h>

namespace spall {

/// How one face meets one charge's wave.
struct FaceExposure {
    /// cos of the angle of incidence, -n . r_hat (n the face's outward normal, r_hat from the
    /// charge): 1 head-on, 0 grazing, negative for faces looking away.
    double cosIncidence = 1.0;
    /// Time over which the reflected pressure relaxes to the stagnation pressure, and a face
    /// looking away builds up its drag (unit: s).
    double clearingTimeS = 1e30;
    /// Time over which the pressure on a rear face (cos = -1) builds up after the wave reaches
    /// it, 4S/U for the body's silhouette (UFC 3-340-02 §2-15.4, rear wall); a face at incidence
    /// a > 90 degrees takes -cos(a) of it (unit: s).
    double rearRiseTimeS = 0.0;
    /// The fraction of the normally reflected excess (Pr - Ps) the face sees at its incidence
    /// (loads/ObliqueReflection.h): 1 head-on, 0 at grazing and on faces looking away.
    double reflectedFraction = 1.0;
};

/// How a face at incidence cos(alpha) meets `pulse`: its reflected fraction from the pulse's
/// peak side-on pressure (the angle dependence is taken at the peak, for the whole pulse).
FaceExposure faceExposure(const PointPulse& pulse, double cosIncidence, double clearingTimeS, double rearRiseTimeS, double ambientPa);

/// Drag coefficient of a face against its angle of incidence: +1 head-on (UFC 3-340-02 §2-15.3,
/// front wall), -0.4 at grazing incidence (side walls and roof, for dynamic pressures up to
/// 25 psi) and -0.25 on the rear face (rear wall), joined by quadratics in cos so that the load
/// is continuous as a face turns (unit: 1).
double dragCoefficient(double cosIncidence);

/// Peak dynamic pressure behind a shock of side-on overpressure ps in air at ambient p0,
/// q = 5 ps^2 / (2 (ps + 7 p0)) (Rankine–Hugoniot, gamma = 1.4; blast-data.md §5) (unit: Pa).
inline double dynamicPressurePa(double ps, double p0) { return ps > 0.0 ? 2.5 * ps * ps / (ps + 7.0 * p0) : 0.0; }

/// Clearing time of a face region S by G (S the smaller of its half-width and height above
/// the ground, G the larger) under a shock of speed U: tc = 4 S / ((1 + S/G) U) (UFC 3-340-02
/// eq. 2-4) (unit: s).
inline double clearingTimeS(double smallerM, double largerM, double shockSpeedMS)
{
    return 4.0 * smallerM / ((1.0 + smallerM / largerM) * shockSpeedMS);
}

/// Overpressure on the face (unit: Pa, positive pushes into it) at `sinceArrivalS` after the
/// wave reaches it: p = r (s + w (p_a - s)), with s = p_s + Cd q the stagnation pressure,
/// w = max(0, 1 - tau/tc) the part not yet cleared, r the rise on faces looking away, and p_a
/// the reflected pressure at incidence a, p_a = p_s + f (p_r - p_s) with f the face's
/// reflected fraction (p_a = p_s for faces looking away).
double faceOverpressurePa(const PointPulse& pulse, const FaceExposure& face, double sinceArrivalS, double ambientPa);

/// The same pressure integrated from `fromS` to `toS` after arrival (unit: Pa s): Gauss–Legendre
/// on each smooth piece of the pulse (split at arrival, at the end of clearing, at the end of
/// each phase), exact to rounding for steps that are short against the pulse's decay.
double faceImpulsePaS(const PointPulse& pulse, const FaceExposure& face, double fromS, double toS, double ambientPa);

}  // namespace spall
