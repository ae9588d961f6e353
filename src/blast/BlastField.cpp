// The pressure field of many charges, on tables uniform in log Z built once per dataset: the
// lookups, the open windows, and the pressure snapshot a step's link loading reads.
#include <spall/blast/Blast.h>

#include "ReferenceData.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <limits>

namespace spall {

using namespace blastdata;

namespace {

struct MantissaLog2Table {
    std::array<double, 4097> value;
    MantissaLog2Table()
    {
        for (size_t i = 0; i < value.size(); ++i) value[i] = std::log2(1.0 + double(i) / 4096.0);
    }
};
const MantissaLog2Table kMantissaLog2;

}  // namespace

double fastLog2(double x)
{
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const int exponent = static_cast<int>((bits >> 52) & 0x7ff) - 1023;
    const uint64_t mantissa = bits & ((uint64_t(1) << 52) - 1);
    const size_t index = static_cast<size_t>(mantissa >> 40);  // top 12 bits
    const double frac = static_cast<double>(mantissa & ((uint64_t(1) << 40) - 1)) * (1.0 / double(uint64_t(1) << 40));
    const double a = kMantissaLog2.value[index];
    return exponent + a + frac * (kMantissaLog2.value[index + 1] - a);
}

BlastTable::BlastTable(BlastDataset dataset, BurstType burst, int nodesPerDecade)
{
    if (nodesPerDecade < 2 || nodesPerDecade > 100000)
        throw InputError("blast table resolution must be 2..100000 nodes per decade, got " + std::to_string(nodesPerDecade));
    // From the fits' near end to Z = 1000 m/kg^(1/3) (far beyond any scene: Ps ~ 0.1 kPa).
    const double zLo = fittedRange(dataset, burst).lo, zHi = 1000.0;
    mLog2ZMin = std::log2(zLo);
    mNodesPerLog2 = nodesPerDecade / std::log2(10.0);
    const size_t count = static_cast<size_t>(std::ceil((std::log2(zHi) - mLog2ZMin) * mNodesPerLog2)) + 1;
    mNodes.resize(count);
    double runningEnd = 0.0, runningPositiveEnd = 0.0;
    for (size_t i = 0; i < count; ++i) {
        const BlastParameters s = scaledBlastDirect(dataset, burst, scaledDistanceOfNode(double(i)));
        runningEnd = std::max(runningEnd, s.arrivalTimeS + s.positiveDurationS + s.negativeDurationS);
        runningPositiveEnd = std::max(runningPositiveEnd, s.arrivalTimeS + s.positiveDurationS);
        mNodes[i] = {s.arrivalTimeS,       s.positiveDurationS,         s.peakOverpressurePa, s.decayCoefficient,
                     s.negativePeakPa,     runningEnd,                  runningPositiveEnd,   s.reflectedPressurePa,
                     s.reflectedDecayCoefficient, s.shockSpeedMS};
    }
}

double BlastTable::frontScaledDistance(double tau) const
{
    if (tau <= mNodes.front().arrivalTimeS) return scaledDistanceOfNode(0.0) * std::max(tau, 0.0) / mNodes.front().arrivalTimeS;
    if (tau >= mNodes.back().arrivalTimeS) return scaledDistanceMax() + (tau - mNodes.back().arrivalTimeS) * mSoundSpeedMS;
    auto it = std::upper_bound(mNodes.begin(), mNodes.end(), tau,
                               [](double t, const Node& n) { return t < n.arrivalTimeS; });
    // One cell beyond the crossing node: conservative, the front is never outside the range.
    const size_t i = std::min<size_t>(static_cast<size_t>(it - mNodes.begin()) + 1, mNodes.size() - 1);
    return scaledDistanceOfNode(double(i));
}

double BlastTable::rearScaledDistance(double tau) const
{
    if (tau < mNodes.front().windowEndS) return 0.0;
    if (tau >= mNodes.back().windowEndS) return scaledDistanceMax() + (tau - mNodes.back().windowEndS) * mSoundSpeedMS;
    auto it = std::upper_bound(mNodes.begin(), mNodes.end(), tau,
                               [](double t, const Node& n) { return t < n.windowEndS; });
    const size_t first = static_cast<size_t>(it - mNodes.begin());  // first node still open
    return first >= 2 ? scaledDistanceOfNode(double(first - 2)) : 0.0;
}

BlastField::BlastField(std::vector<Charge> charges, const BlastSettings& settings)
    : mCharges(std::move(charges)), mSettings(settings), mNegativeDurationScaledS(kNegativeDurationScaledS)
{
    const Atmosphere& a = settings.atmosphere;
    if (!(a.pressurePa > 0) || !(a.temperatureK > 0)) throw InputError("atmosphere pressure_Pa and temperature_K must be positive");
    mSpeedScale = SachsScaling(1.0, a).speedScale;
    mTables.reserve(2);
    mTables.emplace_back(settings.dataset, BurstType::FreeAir, settings.tableNodesPerDecade);
    mTables.emplace_back(settings.dataset, BurstType::Surface, settings.tableNodesPerDecade);
    for (size_t i = 0; i < mCharges.size(); ++i) {
        const Charge& c = mCharges[i];
        if (!(c.tntKg > 0.0) || !std::isfinite(c.tntKg))
            throw InputError("charge " + std::to_string(i) + ": tnt_kg must be positive and finite");
        if (!c.positionM.allFinite() || !std::isfinite(c.detonationTimeS))
            throw InputError("charge " + std::to_string(i) + ": position_m and detonation_time_s must be finite");
        const SachsScaling sachs(c.tntKg, a);
        PerCharge pc;
        pc.table = &mTables[c.burst == BurstType::FreeAir ? 0 : 1];
        pc.detonationTimeS = c.detonationTimeS;
        pc.lengthScale = sachs.lengthScale;
        pc.log2LengthScale = std::log2(pc.lengthScale);
        pc.timeScale = sachs.timeScale;
        pc.pressureScale = sachs.pressureScale;
        mPerCharge.push_back(pc);
    }
}

std::vector<OpenWindow> BlastField::openWindows(double timeS) const
{
    std::vector<OpenWindow> windows;
    for (size_t i = 0; i < mCharges.size(); ++i) {
        const PerCharge& c = mPerCharge[i];
        const double tau = (timeS - c.detonationTimeS) / c.timeScale;
        if (tau <= 0.0) continue;
        OpenWindow w;
        w.charge = static_cast<int>(i);
        w.minDistanceM = c.table->rearScaledDistance(tau) / c.lengthScale;
        w.maxDistanceM = c.table->frontScaledDistance(tau) / c.lengthScale;
        if (w.maxDistanceM > w.minDistanceM) windows.push_back(w);
    }
    return windows;
}

std::pair<double, double> BlastField::window(int charge, double distanceM) const
{
    const BlastParameters p = tableParameters(charge, distanceM);
    const double start = mCharges[charge].detonationTimeS + p.arrivalTimeS;
    return {start, start + p.positiveDurationS + p.negativeDurationS};
}

BlastParameters BlastField::tableParameters(int charge, double distanceM) const
{
    const PerCharge& c = mPerCharge[charge];
    const BlastTable::Node n = c.table->lookupLog2(std::log2(distanceM) + c.log2LengthScale);
    BlastParameters p;
    p.scaledDistanceMKg13 = distanceM * c.lengthScale;
    p.peakOverpressurePa = n.peakOverpressurePa * c.pressureScale;
    p.arrivalTimeS = n.arrivalTimeS * c.timeScale;
    p.positiveDurationS = n.positiveDurationS * c.timeScale;
    p.decayCoefficient = n.decayCoefficient;
    p.negativePeakPa = n.negativePeakPa * c.pressureScale;
    p.negativeDurationS = mNegativeDurationScaledS * c.timeScale;
    p.reflectedPressurePa = n.reflectedPeakPa * c.pressureScale;
    p.reflectedDecayCoefficient = n.reflectedDecayCoefficient;
    p.shockSpeedMS = n.shockSpeedMS * mSpeedScale;
    return p;
}

double BlastField::latestPositiveEndS(int charge, double distanceM) const
{
    const PerCharge& c = mPerCharge[charge];
    return c.detonationTimeS + c.table->lookupLog2(std::log2(distanceM) + c.log2LengthScale).positiveEndS * c.timeScale;
}

PointPulse BlastField::pulseAt(int charge, double distanceSquaredM2) const
{
    const PerCharge& c = mPerCharge[charge];
    const BlastTable::Node n = c.table->lookupLog2(0.5 * fastLog2(distanceSquaredM2) + c.log2LengthScale);
    PointPulse p;
    p.arrivalTimeS = c.detonationTimeS + n.arrivalTimeS * c.timeScale;
    p.positiveDurationS = n.positiveDurationS * c.timeScale;
    p.peakOverpressurePa = n.peakOverpressurePa * c.pressureScale;
    p.decayCoefficient = n.decayCoefficient;
    p.reflectedPeakPa = n.reflectedPeakPa * c.pressureScale;
    p.reflectedDecayCoefficient = n.reflectedDecayCoefficient;
    p.negativePeakPa = n.negativePeakPa * c.pressureScale;
    p.negativeDurationS = mNegativeDurationScaledS * c.timeScale;
    p.shockSpeedMS = n.shockSpeedMS * mSpeedScale;
    return p;
}

double BlastField::shockSpeedMS(int charge, double distanceM) const
{
    // Sound speed, and with it the shock speed, scales with sqrt(T); T > 0 is checked on construction.
    return tableParameters(charge, distanceM).shockSpeedMS;
}

}  // namespace spall

namespace spall {

PressureSnapshot::PressureSnapshot(const BlastField& field, double timeS, double stepS) : mWindows(field.openWindows(timeS))
{
    constexpr double kNearestM = 1e-6;  // the fits are clamped there anyway; keeps log(0) out
    mProfiles.resize(mWindows.size());
    for (size_t w = 0; w < mWindows.size(); ++w) {
        const OpenWindow& window = mWindows[w];
        const Charge& charge = field.charges()[window.charge];
        Profile& profile = mProfiles[w];
        profile.centreM = charge.positionM;
        profile.innerM = std::max(window.minDistanceM, kNearestM);
        // The fronts: the farthest distance the shock has reached by a time (arrival time
        // grows with distance), or -1 when it has not reached the inner edge.
        const auto frontAt = [&](double atS) {
            const auto arrived = [&](double r) { return charge.detonationTimeS + field.tableParameters(window.charge, r).arrivalTimeS <= atS; };
            if (!arrived(profile.innerM)) return -1.0;
            double lo = profile.innerM, hi = std::max(window.maxDistanceM, lo);
            for (int grow = 0; grow < 64 && arrived(hi); ++grow) lo = hi, hi *= 1.5;
            for (int i = 0; i < 64 && hi - lo > 1e-12 * hi; ++i) {
                const double mid = 0.5 * (lo + hi);
                (arrived(mid) ? lo : hi) = mid;
            }
            return lo;
        };
        const double startFront = frontAt(timeS);
        profile.frontM = frontAt(timeS + stepS);
        profile.overpressurePa.assign(kNodesPerWindow, 0.0);
        if (profile.frontM < profile.innerM) continue;  // nothing has arrived inside the window yet
        const double step = (profile.frontM - profile.innerM) / (kNodesPerWindow - 1);
        profile.nodesPerM = step > 0 ? 1.0 / step : 0.0;
        for (int i = 0; i < kNodesPerWindow; ++i) {
            const double r = i + 1 == kNodesPerWindow ? profile.frontM : profile.innerM + i * step;
            profile.overpressurePa[i] = r <= startFront ? field.chargeOverpressurePa(window.charge, r, timeS)
                                                        : field.tableParameters(window.charge, r).peakOverpressurePa;
        }
    }
}

double PressureSnapshot::maxOverShellPa(size_t window, double rMinM, double rMaxM) const
{
    const Profile& p = mProfiles[window];
    const double lo = std::max(rMinM, p.innerM), hi = std::min(rMaxM, p.frontM);
    if (!(lo <= hi)) return 0.0;
    // Outside [inner, front] the pressure is zero, which bounds it too.
    double most = rMinM < p.innerM || rMaxM > p.frontM ? 0.0 : -std::numeric_limits<double>::infinity();
    const size_t last = p.overpressurePa.size() - 1;
    const size_t first = std::min(static_cast<size_t>((lo - p.innerM) * p.nodesPerM), last);
    const size_t end = std::min(static_cast<size_t>(std::ceil((hi - p.innerM) * p.nodesPerM)), last);
    for (size_t i = first; i <= end; ++i) most = std::max(most, p.overpressurePa[i]);
    return most;
}

}  // namespace spall
