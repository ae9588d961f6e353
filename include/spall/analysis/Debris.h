// Where the debris lands: each fragment's flight read from a run's history (launch, peak and
// impact energy, resting place), and the figures safety engineers ask of them: throw distances,
// areal densities by ring and sector, hazardous fragments (DDESB TP 12: at least 79 J, one per
// 55.7 m^2), and the mass distribution's Weibull (Grady-Mott) fit. Definitions:
// docs/debris.md.
#pragma once

#include <spall/output/History.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace spall {

struct DebrisSettings {
    double hazardousEnergyJ = 79.0;   ///< DDESB TP 12's criterion, 58 ft-lb (unit: J)
    double hazardousAreaM2 = 55.7;    ///< one hazardous fragment per this area, 600 ft^2 (unit: m^2)
    double launchSpeedMS = 0.5;       ///< a fragment is launched once it moves this fast (unit: m/s)
    /// A piece resting within this distance (horizontally) of where it was when it came to be
    /// stayed where it stood: a stump, not debris (unit: m).
    double stayDistanceM = 0.1;
    double ringWidthM = 0.0;          ///< 0: a round width giving about 20 rings to the farthest piece (unit: m)
    int sectors = 8;                  ///< equal sectors about the origin, the first centred on +x (unit: 1)
};

/// One fragment of the last frame followed back through its ancestors: in each frame the body
/// it was part of (itself, or the ancestor it later split from).
struct FragmentFlight {
    int64_t id = 0;
    double massKg = 0;
    bool anchored = false;  ///< still held by the ground
    bool stayed = false;    ///< anchored, or resting where it stood (DebrisSettings::stayDistanceM): not debris
    bool launched = false;
    double launchTimeS = 0;
    Eigen::Vector3d launchPositionM = Eigen::Vector3d::Zero(), launchVelocityMS = Eigen::Vector3d::Zero();
    double peakKineticEnergyJ = 0;  ///< largest 1/2 m v^2 from launch to impact (or the end) (unit: J)
    bool impacted = false;
    double impactTimeS = 0;
    Eigen::Vector3d impactPositionM = Eigen::Vector3d::Zero();
    double impactKineticEnergyJ = 0;  ///< 1/2 m v^2 in the frame before the impact (unit: J)
    Eigen::Vector3d restPositionM = Eigen::Vector3d::Zero();  ///< in the last frame
    double throwDistanceM = 0;  ///< horizontal distance from the origin to the resting place (unit: m)
    bool hazardous = false;     ///< impacted with at least DebrisSettings::hazardousEnergyJ
};

/// One ring of the polar grid about the origin, with its sectors.
struct DebrisRing {
    double innerM = 0, outerM = 0;
    int64_t fragments = 0;              ///< resting in the ring
    double massKg = 0;
    int64_t hazardous = 0;              ///< hazardous fragments whose impact point lies in the ring
    std::vector<int64_t> sectorFragments, sectorHazardous;
    double areaM2() const;
    double fragmentDensityPerM2() const { return fragments / areaM2(); }
    double hazardousDensityPerM2() const { return hazardous / areaM2(); }
    /// The densest sector's hazardous density (unit: 1/m^2).
    double worstSectorHazardousDensityPerM2() const;
};

/// N(>m) = N exp(-(m/scale)^shape) fitted by least squares to ln(-ln(rank/N)) against ln m
/// (Mott's distribution is shape 1/2; Grady, Fragmentation of Rings and Shells, 2006, ch. 1).
struct WeibullMassFit {
    int64_t fragments = 0;  ///< fitted; 0 when fewer than three distinct masses
    double shape = 0;
    double scaleKg = 0;
    double rSquared = 0;    ///< of the linearised fit
};

struct DebrisReport {
    Eigen::Vector3d originM = Eigen::Vector3d::Zero();  ///< the charges' TNT-weighted centre
    DebrisSettings settings;
    std::vector<FragmentFlight> fragments;              ///< debris and stumps, in id order
    std::vector<DebrisRing> rings;
    double maxThrowDistanceM = 0;
    double medianThrowDistanceM = 0, massMedianThrowDistanceM = 0;  ///< by count, by mass
    /// Outer radius of the farthest ring where hazardous fragments are denser than one per
    /// hazardousAreaM2: over the whole ring, and in its densest sector (directional debris) (unit: m).
    double hazardousFragmentDistanceM = 0, worstSectorHazardousFragmentDistanceM = 0;
    WeibullMassFit massFit;
    int64_t debrisCount() const;
    int64_t hazardousCount() const;
};

/// The analysis of a history (the last frame's bodies). Throws InputError when the history has
/// no frames or no charges.
DebrisReport analyseDebris(const History& history, const DebrisSettings& settings = {});

/// Writes OUTDIR/debris.h5, OUTDIR/debris.csv (a row per fragment) and the plots
/// OUTDIR/debris_throw.png, debris_density.png, debris_mass.png; each whole or not at all.
void writeDebrisReport(const std::string& outDir, const DebrisReport& report);

}  // namespace spall
