// How the reflected pressure on a face depends on the angle at which the shock meets it: regular
// reflection from ideal-gas two-shock theory up to the angle where it can no longer exist, Mach
// reflection beyond it (the pattern of UFC 3-340-02 Fig. 2-193: the reflection coefficient
// holds, rises to a peak near the transition, then falls to side-on at grazing incidence).
#pragma once

namespace spall {

/// Regular reflection of a plane shock of overpressure ratio xi = p1/p0 meeting a rigid wall at
/// angle of incidence alpha (between the shock's direction of travel and the wall's normal),
/// in an ideal gas of gamma = 1.4 (two-shock theory: the incident oblique shock turns the flow
/// toward the wall by theta, the reflected shock turns it back; Ben-Dor, "Shock Wave
/// Reflection Phenomena", 2nd ed., ch. 1).
struct TwoShockReflection {
    bool regular = false;           ///< false beyond the detachment angle (Mach reflection)
    double pressureRatio = 1.0;     ///< p2/p0 behind the reflected shock (regular only)
};
TwoShockReflection twoShockReflection(double pressureRatio, double incidenceRad);

/// The angle of incidence beyond which regular reflection cannot exist for a shock of
/// overpressure ratio xi (unit: rad).
double detachmentAngleRad(double pressureRatio);

/// The fraction of the normally reflected excess (Pr - Ps) that a face sees at incidence
/// cos(alpha), for a shock of side-on overpressure `sideOnPa` in air at `ambientPa`: the ideal
/// gas's (P(alpha) - Ps) / (Pr(0) - Ps). Regular reflection up to the detachment angle; beyond
/// it the Mach stem's pressure, taken to fall from the regular value at detachment to side-on
/// at grazing incidence as (cos alpha / cos alpha_d)^2. 0 for faces looking away. Read from a
/// table over log(xi) and alpha built once.
double reflectedExcessFraction(double sideOnPa, double ambientPa, double cosIncidence);

}  // namespace spall
