// The blast wave (paper sections 2.1 and 3.1): reference TNT data scaled by the cube root of the
// charge, the modified Friedlander positive phase, a separate negative phase, many charges.
// Formulas, coefficients and check values: shared/reference/blast-data.md (sources cited in Blast.cpp).
#pragma once

#include <spall/blast/Settings.h>
#include <spall/core/Error.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace spall {


/// Where a scaled distance lies relative to the dataset's fitted range.
enum class RangeStatus { Inside, ClampedNear, ExtrapolatedFar };

/// Every blast parameter at one point, in SI units. From scaledBlastDirect they are those of a
/// 1 kg sea-level charge (Hopkinson–Cranz units: times in s/kg^(1/3), impulse in Pa s/kg^(1/3)).
struct BlastParameters {
    double scaledDistanceMKg13 = 0;
    double peakOverpressurePa = 0;
    double arrivalTimeS = 0;
    double positiveDurationS = 0;
    double positiveImpulsePaS = 0;
    double decayCoefficient = 0;
    double negativePeakPa = 0;
    double negativeDurationS = 0;
    double reflectedPressurePa = 0;   ///< normally reflected peak Pr
    double reflectedImpulsePaS = 0;   ///< normally reflected positive impulse Ir
    /// Friedlander decay of the reflected pulse: Pr over T+ carrying Ir (unit: 1).
    double reflectedDecayCoefficient = 0;
    double shockSpeedMS = 0;
    RangeStatus status = RangeStatus::Inside;
};

/// One charge's pulse at one point, in real units: what the loads stage turns into face pressures.
struct PointPulse {
    double arrivalTimeS = 0;  ///< absolute (detonation time included)
    double positiveDurationS = 0;
    double peakOverpressurePa = 0;  ///< side-on
    double decayCoefficient = 0;
    double reflectedPeakPa = 0;  ///< normally reflected, Kingery–Bulmash Pr
    double reflectedDecayCoefficient = 0;
    double negativePeakPa = 0;
    double negativeDurationS = 0;
    double shockSpeedMS = 0;
};

/// Direct evaluation of the dataset's fits (polynomials or closed forms) at scaled distance Z
/// (unit: m/kg^(1/3)). Below the fitted range values are held at its near end; beyond it they
/// are extrapolated (power laws for Ps and Is, sound speed for ta); `status` says which.
BlastParameters scaledBlastDirect(BlastDataset dataset, BurstType burst, double scaledDistance);

/// Every parameter of a charge of `tntKg` at `distanceM` (Sachs-scaled). Validates inputs
/// (throws InputError naming the field) and evaluates the direct fits.
BlastParameters blastParameters(BlastDataset dataset, BurstType burst, double tntKg, double distanceM,
                                const Atmosphere& atmosphere = {});

/// Friedlander decay coefficient b such that the pulse carries impulse fraction
/// k = Is / (Ps T+) (blast-data.md §3); any k > 0, b <= 0 included.
double solveDecayCoefficient(double impulseFraction);
/// Impulse fraction k(b) = 1/b - (1 - e^-b)/b^2, with its series near b = 0.
double friedlanderImpulseFraction(double b);

/// Overpressure (p - p0, unit: Pa) of the positive phase at time s after arrival, 0 <= s <= T.
inline double friedlanderOverpressure(double peakPa, double durationS, double b, double s)
{
    const double x = s / durationS;
    return peakPa * (1.0 - x) * std::exp(-b * x);
}

/// Negative phase after T+: cubic pulse of NAVFAC DM-2.08 eq. 14a, peak -Ps- at tau = T-/3.
inline double negativePhaseOverpressure(double negativePeakPa, double negativeDurationS, double tau)
{
    const double x = tau / negativeDurationS;
    return -negativePeakPa * 6.75 * x * (1.0 - x) * (1.0 - x);
}

/// The whole pulse at time s after arrival: zero before it, the Friedlander positive phase for
/// T+, the negative phase for T-, zero after (unit: Pa). The one pulse every path evaluates.
inline double pulseOverpressure(double peakPa, double positiveDurationS, double decayCoefficient, double negativePeakPa,
                                double negativeDurationS, double s)
{
    if (s < 0.0) return 0.0;
    if (s <= positiveDurationS) return friedlanderOverpressure(peakPa, positiveDurationS, decayCoefficient, s);
    const double tau = s - positiveDurationS;
    if (tau < negativeDurationS) return negativePhaseOverpressure(negativePeakPa, negativeDurationS, tau);
    return 0.0;
}

/// Overpressure history at one point from its parameters (time since detonation).
inline double overpressureAt(const BlastParameters& p, double timeSinceDetonationS)
{
    return pulseOverpressure(p.peakOverpressurePa, p.positiveDurationS, p.decayCoefficient, p.negativePeakPa, p.negativeDurationS,
                             timeSinceDetonationS - p.arrivalTimeS);
}

/// Normal reflection of a shock of side-on overpressure ps in an ideal gas (gamma = 1.4) at
/// ambient pressure p0 (Rankine–Hugoniot; blast-data.md §6) (unit: Pa).
inline double rankineHugoniotReflected(double ps, double p0) { return 2.0 * ps * (7.0 * p0 + 4.0 * ps) / (7.0 * p0 + ps); }

/// Sachs scaling of a charge in an atmosphere (blast-data.md §5): from the reference 1 kg charge
/// at sea level to this one.
struct SachsScaling {
    double lengthScale;    ///< Z / R (unit: kg^(-1/3))
    double timeScale;      ///< real time / scaled time (unit: kg^(1/3))
    double pressureScale;  ///< p0 / sea-level p0
    double impulseScale;   ///< real impulse / scaled impulse
    double speedScale;     ///< sqrt(T0 / sea-level T0)
    SachsScaling(double tntKg, const Atmosphere& atmosphere);
};

/// A charge of TNT.
/// log2(x) for finite x > 0 without a libm call: exponent bits plus a 4097-entry mantissa table
/// with linear interpolation (absolute error below 1.1e-8).
double fastLog2(double x);

/// Sea-level scaled quantities tabulated uniformly in log Z, built once per dataset and burst.
class BlastTable {
public:
    struct Node {
        double arrivalTimeS, positiveDurationS, peakOverpressurePa, decayCoefficient, negativePeakPa;
        double windowEndS;    ///< arrival + T+ + T-, running maximum from the near end
        double positiveEndS;  ///< arrival + T+, running maximum from the near end
        double reflectedPeakPa, reflectedDecayCoefficient, shockSpeedMS;
    };
    BlastTable(BlastDataset dataset, BurstType burst, int nodesPerDecade);

    /// Linear interpolation in log Z; log2 Z outside the table clamps to its ends.
    Node lookupLog2(double log2Z) const
    {
        double u = (log2Z - mLog2ZMin) * mNodesPerLog2;
        if (u <= 0.0) return mNodes.front();
        const double last = static_cast<double>(mNodes.size() - 1);
        if (u >= last) return mNodes.back();
        const size_t i = static_cast<size_t>(u);
        const double w = u - static_cast<double>(i);
        const Node& a = mNodes[i];
        const Node& b = mNodes[i + 1];
        return {a.arrivalTimeS + w * (b.arrivalTimeS - a.arrivalTimeS),
                a.positiveDurationS + w * (b.positiveDurationS - a.positiveDurationS),
                a.peakOverpressurePa + w * (b.peakOverpressurePa - a.peakOverpressurePa),
                a.decayCoefficient + w * (b.decayCoefficient - a.decayCoefficient),
                a.negativePeakPa + w * (b.negativePeakPa - a.negativePeakPa),
                a.windowEndS + w * (b.windowEndS - a.windowEndS),
                a.positiveEndS + w * (b.positiveEndS - a.positiveEndS),
                a.reflectedPeakPa + w * (b.reflectedPeakPa - a.reflectedPeakPa),
                a.reflectedDecayCoefficient + w * (b.reflectedDecayCoefficient - a.reflectedDecayCoefficient),
                a.shockSpeedMS + w * (b.shockSpeedMS - a.shockSpeedMS)};
    }
    double scaledDistanceMax() const { return std::exp2(mLog2ZMin + double(mNodes.size() - 1) / mNodesPerLog2); }
    /// Scaled distance of the shock front at scaled time tau (s/kg^(1/3)).
    double frontScaledDistance(double tauS) const;
    /// Largest scaled distance at which the window [ta, ta+T++T-] has closed by tau.
    double rearScaledDistance(double tauS) const;

private:
    double scaledDistanceOfNode(double u) const { return std::exp2(mLog2ZMin + u / mNodesPerLog2); }
    double mLog2ZMin = 0;
    double mNodesPerLog2 = 1;
    std::vector<Node> mNodes;
    double mSoundSpeedMS = 340.29;
};

/// Distances (unit: m) from one charge where its pressure window is open at a given time.
struct OpenWindow {
    int charge = 0;
    double minDistanceM = 0;
    double maxDistanceM = 0;
};

/// Overpressure at one point from all charges, with the dominant charge: the one whose
/// overpressure there is the largest positive (the wave that pushes hardest; none in a pure
/// negative phase). Weakening and orientation (fracture) follow the dominant charge.
struct PressureSample {
    double overpressurePa = 0;
    int dominantCharge = -1;
    size_t dominantWindow = 0;  ///< its window's index among those sampled
    double dominantOverpressurePa = 0;

    void add(size_t window, int charge, double p)
    {
        overpressurePa += p;
        if (p > dominantOverpressurePa) {
            dominantOverpressurePa = p;
            dominantCharge = charge;
            dominantWindow = window;
        }
    }
};

/// The pressure field of all charges. Thread-safe for concurrent queries.
class BlastField {
public:
    BlastField(std::vector<Charge> charges, const BlastSettings& settings);

    const std::vector<Charge>& charges() const { return mCharges; }
    const BlastSettings& settings() const { return mSettings; }

    /// Charges whose window is open somewhere at time t, with the open distance range (padded
    /// by one table cell, so nothing inside is ever skipped).
    std::vector<OpenWindow> openWindows(double timeS) const;

    /// Window [start, end] (absolute times, unit: s) of a charge at a distance.
    std::pair<double, double> window(int charge, double distanceM) const;

    /// Overpressure at a world point (unit: Pa) from the charges in `windows` (from openWindows
    /// at the same time). Costs a fast log2, table reads and one exp per charge in range.
    PressureSample sample(const Eigen::Vector3d& pointM, double timeS, const std::vector<OpenWindow>& windows) const
    {
        PressureSample out;
        for (size_t i = 0; i < windows.size(); ++i) {
            const OpenWindow& w = windows[i];
            const double r2 = (pointM - mCharges[w.charge].positionM).squaredNorm();
            if (r2 < w.minDistanceM * w.minDistanceM || r2 > w.maxDistanceM * w.maxDistanceM) continue;
            out.add(i, w.charge, chargeOverpressure(mPerCharge[w.charge], r2, timeS));
        }
        return out;
    }

    /// Calls f(chargeIndex, overpressurePa, chargePositionM) for every charge in `windows` whose
    /// window holds the point, for loads that need each charge's direction.
    template <typename F>
    void forEachCharge(const Eigen::Vector3d& pointM, double timeS, const std::vector<OpenWindow>& windows, F&& f) const
    {
        for (const OpenWindow& w : windows) {
            const Eigen::Vector3d& c = mCharges[w.charge].positionM;
            const double r2 = (pointM - c).squaredNorm();
            if (r2 < w.minDistanceM * w.minDistanceM || r2 > w.maxDistanceM * w.maxDistanceM) continue;
            const double p = chargeOverpressure(mPerCharge[w.charge], r2, timeS);
            if (p != 0.0) f(w.charge, p, c);
        }
    }

    /// Convenience for callers outside hot loops.
    double overpressurePa(const Eigen::Vector3d& pointM, double timeS) const
    {
        return sample(pointM, timeS, openWindows(timeS)).overpressurePa;
    }

    /// Overpressure of one charge at a distance (unit: Pa), whether or not its window is open.
    double chargeOverpressurePa(int charge, double distanceM, double timeS) const
    {
        return chargeOverpressure(mPerCharge[charge], distanceM * distanceM, timeS);
    }

    /// Shock front speed (unit: m/s) of a charge at a distance; for time-step control.
    double shockSpeedMS(int charge, double distanceM) const;

    /// Parameters of one charge at a distance from the table (what the hot path uses).
    BlastParameters tableParameters(int charge, double distanceM) const;
    /// The latest time (unit: s, detonation included) at which the positive phase of one charge
    /// ends anywhere within distanceM of it. Near a charge the positive duration can fall faster
    /// than the arrival grows, so the positive phase need not end last at the farthest point.
    double latestPositiveEndS(int charge, double distanceM) const;
    /// One charge's pulse at squared distance r2 (unit: m^2), from the table.
    PointPulse pulseAt(int charge, double distanceSquaredM2) const;

private:
    struct PerCharge {
        const BlastTable* table;
        double detonationTimeS;
        double log2LengthScale;  ///< log2 of Z/R
        double lengthScale;      ///< Z/R (unit: kg^(-1/3), Sachs-scaled)
        double timeScale;        ///< real time / scaled time
        double pressureScale;    ///< p / p0 (Sachs)
    };
    double chargeOverpressure(const PerCharge& c, double r2, double timeS) const
    {
        const double tau = (timeS - c.detonationTimeS) / c.timeScale;
        const BlastTable::Node n = c.table->lookupLog2(0.5 * fastLog2(r2) + c.log2LengthScale);
        // In scaled units: the table's pulse, then the pressure scale.
        return c.pressureScale * pulseOverpressure(n.peakOverpressurePa, n.positiveDurationS, n.decayCoefficient, n.negativePeakPa,
                                                   mNegativeDurationScaledS, tau - n.arrivalTimeS);
    }

    std::vector<Charge> mCharges;
    BlastSettings mSettings;
    std::vector<BlastTable> mTables;  ///< [0] free air, [1] surface
    std::vector<PerCharge> mPerCharge;
    double mNegativeDurationScaledS;
    double mSpeedScale = 1;  ///< sound and shock speeds scale with sqrt(T) (Sachs)
};

/// The pressure field over one step, for the many points a step queries (every link of every
/// loaded body): the largest overpressure each point sees during the step, so that a threshold
/// does not depend on where the step falls on the pulse. Behind the shock front at the step's
/// start that is the pressure then (the positive phase only falls); between that front and
/// the front at its end it is the peak the shock brings. Per open window, that overpressure is
/// tabulated uniformly in distance from the window's inner edge to the front at the step's end,
/// which is itself the last node, so the jump at the front is exact and nothing is smeared.
/// A point then costs one square root and one linear interpolation per charge instead of a
/// log, a table lookup and an exp; tests/test_blast.cpp bounds the difference to the field.
class PressureSnapshot {
public:
    /// Nodes per window: the window spans the pulse, a few decay lengths, so this resolves it.
    static constexpr int kNodesPerWindow = 2048;

    /// The step [timeS, timeS + stepS]; stepS = 0 gives the field at one instant.
    PressureSnapshot(const BlastField& field, double timeS, double stepS);

    const std::vector<OpenWindow>& windows() const { return mWindows; }
    bool empty() const { return mWindows.empty(); }
    const Eigen::Vector3d& chargePositionM(size_t window) const { return mProfiles[window].centreM; }
    /// Distance range (unit: m) of window w where its pressure is non-zero: [inner edge, front].
    double innerM(size_t window) const { return mProfiles[window].innerM; }
    double frontM(size_t window) const { return mProfiles[window].frontM; }

    /// Overpressure of window w's charge at distance r (unit: Pa).
    double overpressurePa(size_t window, double distanceM) const { return mProfiles[window].at(distanceM); }

    /// Calls f(windowIndex, chargeIndex, overpressurePa) for every window whose pressure at the
    /// point is non-zero.
    template <typename F>
    void forEachCharge(const Eigen::Vector3d& pointM, F&& f) const
    {
        for (size_t w = 0; w < mProfiles.size(); ++w) {
            const double p = mProfiles[w].at((pointM - mProfiles[w].centreM).norm());
            if (p != 0.0) f(w, mWindows[w].charge, p);
        }
    }

    /// Total overpressure at a point (unit: Pa) and the charge that contributes most.
    PressureSample sample(const Eigen::Vector3d& pointM) const
    {
        PressureSample out;
        forEachCharge(pointM, [&](size_t window, int charge, double p) { out.add(window, charge, p); });
        return out;
    }

    /// An upper bound of window w's overpressure anywhere at distances [rMin, rMax] (unit: Pa),
    /// exact for the tabulated profile (its maximum over a cell lies on a node).
    double maxOverShellPa(size_t window, double rMinM, double rMaxM) const;

private:
    struct Profile {
        Eigen::Vector3d centreM;
        double innerM = 0;    ///< distance of node 0
        double frontM = 0;    ///< distance of the last node: the shock front at the step's end
        double nodesPerM = 0;
        std::vector<double> overpressurePa;
        double at(double r) const
        {
            if (!(r >= innerM && r <= frontM)) return 0.0;
            const double u = (r - innerM) * nodesPerM;
            const size_t i = std::min(static_cast<size_t>(u), overpressurePa.size() - 2);
            const double w = u - static_cast<double>(i);
            return overpressurePa[i] + w * (overpressurePa[i + 1] - overpressurePa[i]);
        }
    };
    std::vector<OpenWindow> mWindows;
    std::vector<Profile> mProfiles;
};

}  // namespace spall
