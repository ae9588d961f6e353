// Blast data. Coefficients: Kingery & Bulmash (1984), ARBRL-TR-02555, as used by UFC 3-340-02 and
// ConWep; Kinney & Graham (1985), "Explosive Shocks in Air"; negative phase: NAVFAC DM-2.08 eq. 14a
// with Granström's Ps- and T-; Rankine–Hugoniot relations for an ideal gas. All transcribed from
// shared/reference/blast-data.md, which cross-checks the coefficients.
#include <spall/blast/Blast.h>

#include "ReferenceData.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <sstream>

namespace spall {

using namespace blastdata;

namespace {


// Imperial to metric for the hemispherical set (blast-data.md §1.2).
constexpr double kMetricToImperialZ = 2.51999;     // 1 m/kg^(1/3) in ft/lb^(1/3)
constexpr double kPsiToKPa = 6.894757293168;
constexpr double kPerLb13ToPerKg13 = 1.30192;      // (2.20462)^(1/3)
constexpr double kImpulseImperialToMetric = 8.97646;  // psi·ms/lb^(1/3) -> kPa·ms/kg^(1/3)

/// One Kingery–Bulmash fit: U = C0 + C1 log10(Z), log10(value) = sum K_i U^i.
struct KbFit {
    double c0, c1;
    std::vector<double> k;
    double operator()(double z) const
    {
        const double u = c0 + c1 * std::log10(z);
        double y = 0.0;
        for (size_t i = k.size(); i-- > 0;) y = y * u + k[i];
        return std::pow(10.0, y);
    }
};

// §1.1 spherical free-air burst, metric.
const KbFit kFreePs{-0.214362789151, 1.35034249993,
                    {2.611368669, -1.69012801396, 0.00804973591951, 0.336743114941, -0.00516226351334,
                     -0.0809228619888, -0.00478507266747, 0.00793030472242, 0.0007684469735}};
const KbFit kFreePr{-0.214362789151, 1.35034249993,
                    {3.22958031387, -2.21400538997, 0.035119031446, 0.657599992109, 0.0141818951887,
                     -0.243076636231, -0.0158699803158, 0.0492741184234, 0.00227639644004, -0.00397126276058}};
const KbFit kFreeTa{-0.253273111999, 1.37407043777,
                    {0.0720707787637, 1.36456871214, -0.0570035692784, -0.182832224796, 0.0118851436014,
                     0.0432648687627, -0.0007997367834, -0.00436073555033}};
const KbFit kFreeTd1{2.26367268496, 5.11588554305,
                     {-0.686608550419, 0.164953518069, 0.127788499497, 0.00291430135946, 0.00187957449227,
                      0.0173413962543, 0.00269739758043, -0.00361976502798, -0.00100926577934}};
const KbFit kFreeTd2{-1.33361206714, 9.2996288611,
                     {0.23031841078, -0.0297944268969, 0.0306329542941, 0.018340557407, -0.0173964666286,
                      -0.00106321963576, 0.0056206003128, 0.0001618217499, -0.0006860188944}};
const KbFit kFreeTd3{-3.13005805346, 3.1524725364,
                     {0.621036276475, 0.0967031995552, -0.00801302059667, 0.00482705779732, 0.00187587272287,
                      -0.00246738509321, -0.000841116668, 0.0006193291052}};
const KbFit kFreeIs1{2.34723921354, 3.24299066475,
                     {2.38830516757, -0.443749377691, 0.168825414684, 0.0348138030308, -0.010435192824}};
const KbFit kFreeIs2{-1.75305660315, 2.30629231803,
                     {1.55197227115, -0.40463292088, -0.0142721946082, 0.00912366316617, -0.0006750681404,
                      -0.00800863718901, 0.00314819515931, 0.00152044783382, -0.0007470265899}};
const KbFit kFreeIr{-0.204004553231, 1.37882996018, {2.55875660396, -0.903118886091, 0.101771877942, -0.0242139751146}};
const KbFit kFreeU{-0.214362789151, 1.35034249993,
                   {-0.144615443471, -0.650507560471, 0.291320654009, 0.307916322787, -0.183361123489,
                    -0.197740454538, 0.0909119559768, 0.0898926178054, -0.0287370990248, -0.0248730221702,
                    0.00496311705671, 0.00372242076361, -0.0003533736952, -0.0002292913709}};

// §1.2 hemispherical surface burst, imperial (Z in ft/lb^(1/3)).
const KbFit kSurfPs{-0.756579301809, 1.35034249993,
                    {1.9422502013, -1.6958988741, -0.154159376846, 0.514060730593, 0.0988534365274,
                     -0.293912623038, -0.0268112345019, 0.109097496421, 0.00162846756311, -0.0214631030242,
                     0.0001456723382, 0.00167847752266}};
const KbFit kSurfTa{-0.755684472698, 1.37784223635,
                    {-0.173607601251, 1.35706496258, 0.052492798645, -0.196563954086, -0.0601770052288,
                     0.0696360270891, 0.0215297490092, -0.0161658930785, -0.00232531970294, 0.00147752067524}};
const KbFit kSurfTd1{-0.1790217052, 5.25099193925,
                     {-0.728671776005, 0.130143717675, 0.134872511954, 0.0391574276906, -0.00475933664702,
                      -0.00428144598008}};
const KbFit kSurfTd2{-5.85909812338, 9.2996288611,
                     {0.20096507334, -0.0297944268976, 0.030632954288, 0.0183405574086, -0.0173964666211,
                      -0.00106321963633, 0.00562060030977, 0.0001618217499, -0.0006860188944}};
const KbFit kSurfTd3{-4.92699491141, 3.46349745571,
                     {0.572462469964, 0.0933035304009, -0.0005849420883, -0.00226884995013, -0.00295908591505,
                      0.00148029868929}};
const KbFit kSurfIs1{0.832468843425, 3.0760329666,
                     {1.57159240621, -0.502992763686, 0.171335645235, 0.0450176963051, -0.0118964626402}};
const KbFit kSurfIs2{-2.91358616806, 2.40697745406,
                     {0.719852655584, -0.384519026965, -0.0260816706301, 0.00595798753822, 0.014544526107,
                      -0.00663289334734, -0.00284189327204, 0.0013644816227}};

/// Fitted range of scaled distance (unit: m/kg^(1/3)).
/// Granström's negative peak (blast-data.md §4): 0.35/Z bar beyond Z = 3.5, 0.1 bar nearer.
double granstromNegativePeakPa(double z) { return z > 3.5 ? 0.35e5 / z : 0.1e5; }

/// Sea-level Ps, ta, T+, Is, Pr, Ir, U inside the fitted range (SI, per kg^(1/3)).
struct CoreValues {
    double ps, ta, td, is, pr, ir, u;
};

/// A charge on rigid ground acts like one of twice the mass in free air (the hemisphere carries
/// all the energy): scaled distance shrinks by 2^(1/3), scaled times and impulses grow by it.
const double kSurfaceMassFactorCbrt = std::cbrt(2.0);

/// Kingery–Bulmash normally reflected pressure and impulse of a surface burst, from the free-air
/// fits of the equivalent charge of twice the mass (the hemispherical set in blast-data.md has
/// no Pr or Ir fits).
void surfaceReflection(double z, CoreValues& v)
{
    const double zFree = z / kSurfaceMassFactorCbrt;
    v.pr = kFreePr(zFree) * 1e3;
    v.ir = kFreeIr(zFree) * kSurfaceMassFactorCbrt;
}

CoreValues kingeryBulmashFreeAir(double z)
{
    CoreValues v;
    v.ps = kFreePs(z) * 1e3;
    v.pr = kFreePr(z) * 1e3;
    v.ta = kFreeTa(z) * 1e-3;
    // Below Z = 0.147 there is no T+ fit; ConWep holds 10^-0.824 ms/lb^(1/3).
    if (z < 0.147)
        v.td = std::pow(10.0, -0.824) * kPerLb13ToPerKg13 * 1e-3;
    else if (z < 0.888)
        v.td = kFreeTd1(z) * 1e-3;
    else if (z < 2.28)
        v.td = kFreeTd2(z) * 1e-3;
    else
        v.td = kFreeTd3(z) * 1e-3;
    v.is = (z < 0.792 ? kFreeIs1(z) : kFreeIs2(z));  // kPa·ms = Pa·s
    v.ir = kFreeIr(z);
    v.u = kFreeU(z) * 1e3;
    return v;
}

CoreValues kingeryBulmashSurface(double z)
{
    const double zft = z * kMetricToImperialZ;
    const double zlog = std::log10(zft);
    CoreValues v;
    v.ps = kSurfPs(zft) * kPsiToKPa * 1e3;
    v.ta = kSurfTa(zft) * kPerLb13ToPerKg13 * 1e-3;
    double tdImperial;
    if (zlog <= -0.34)
        tdImperial = std::pow(10.0, -0.725);
    else if (zlog <= 0.4048337)
        tdImperial = kSurfTd1(zft);
    else if (zlog <= 0.845098)
        tdImperial = kSurfTd2(zft);
    else
        tdImperial = kSurfTd3(zft);
    v.td = tdImperial * kPerLb13ToPerKg13 * 1e-3;
    v.is = (zlog <= 0.382017 ? kSurfIs1(zft) : kSurfIs2(zft)) * kImpulseImperialToMetric;
    surfaceReflection(z, v);
    v.u = rankineHugoniotShockSpeed(v.ps, kSeaLevelPressurePa);
    return v;
}

double kinneyGrahamPs(double z)
{
    const double ratio = 808.0 * (1.0 + std::pow(z / 4.5, 2)) /
                         (std::sqrt(1.0 + std::pow(z / 0.048, 2)) * std::sqrt(1.0 + std::pow(z / 0.32, 2)) *
                          std::sqrt(1.0 + std::pow(z / 1.35, 2)));
    return ratio * kSeaLevelPressurePa;
}

/// Kinney–Graham arrival time: integral of 1/U along the path (no closed form), Simpson's rule
/// in ln z from a point where the shock is effectively instantaneous.
double kinneyGrahamArrival(double z)
{
    const double a = std::log(1e-4), b = std::log(z);
    const int n = 400;  // even
    const double h = (b - a) / n;
    auto f = [](double lnz) {
        const double zz = std::exp(lnz);
        return zz / rankineHugoniotShockSpeed(kinneyGrahamPs(zz), kSeaLevelPressurePa);
    };
    double sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += f(a + i * h) * ((i & 1) ? 4.0 : 2.0);
    return sum * h / 3.0;
}

CoreValues kinneyGraham(double z)
{
    CoreValues v;
    v.ps = kinneyGrahamPs(z);
    v.td = 980.0 * (1.0 + std::pow(z / 0.54, 10)) /
           ((1.0 + std::pow(z / 0.02, 3)) * (1.0 + std::pow(z / 0.74, 6)) * std::sqrt(1.0 + std::pow(z / 6.9, 2))) * 1e-3;
    // bar·ms/kg^(1/3) -> Pa·s/kg^(1/3): 1 bar·ms = 1e5 Pa * 1e-3 s = 100 Pa·s.
    v.is = 0.067 * std::sqrt(1.0 + std::pow(z / 0.23, 4)) / (z * z * std::cbrt(1.0 + std::pow(z / 1.55, 3))) * 100.0;
    v.ta = kinneyGrahamArrival(z);
    v.pr = rankineHugoniotReflected(v.ps, kSeaLevelPressurePa);
    // Kinney and Graham give no reflected impulse: their Is times Kingery–Bulmash's Ir/Is.
    const double zKb = std::clamp(z, 0.0531, 40.0);
    v.ir = v.is * kFreeIr(zKb) / (zKb < 0.792 ? kFreeIs1(zKb) : kFreeIs2(zKb));
    v.u = rankineHugoniotShockSpeed(v.ps, kSeaLevelPressurePa);
    return v;
}

CoreValues coreValuesRaw(BlastDataset dataset, BurstType burst, double z)
{
    if (dataset == BlastDataset::KinneyGraham) {
        // Kinney–Graham fits free air: a surface burst is the free-air charge of twice the mass.
        if (burst == BurstType::Surface) {
            const double f = kSurfaceMassFactorCbrt;
            CoreValues v = kinneyGraham(z / f);
            v.ta *= f;
            v.td *= f;
            v.is *= f;
            v.ir *= f;
            return v;
        }
        return kinneyGraham(z);
    }
    return burst == BurstType::FreeAir ? kingeryBulmashFreeAir(z) : kingeryBulmashSurface(z);
}

/// The Kingery–Bulmash free-air ta fit implies a front slower than sound for Z of about 23–40
/// (dta/dZ up to 1.6 % above 1/c0), which no shock does. Arrival times therefore follow the lower
/// envelope of the fit with slope at most 1/c0: ta(Z) = Z/c0 + min over Z' <= Z of (ta_fit(Z') - Z'/c0),
/// precomputed on a fine grid in log Z.
class ArrivalEnvelope {
public:
    ArrivalEnvelope(BlastDataset dataset, BurstType burst)
    {
        const ZRange range = fittedRange(dataset, burst);
        mLogLo = std::log(range.lo);
        const double logHi = std::log(range.hi);
        const int count = 4096;
        mStep = (logHi - mLogLo) / (count - 1);
        double runningMin = 1e300;
        mMinExcess.resize(count);
        for (int i = 0; i < count; ++i) {
            const double z = std::exp(mLogLo + i * mStep);
            runningMin = std::min(runningMin, coreValuesRaw(dataset, burst, z).ta - z / kSoundSpeedMS);
            mMinExcess[i] = runningMin;
        }
    }
    double arrival(double z, double fitArrival) const
    {
        const double u = (std::log(z) - mLogLo) / mStep;
        const int i = std::clamp(static_cast<int>(std::floor(u)), -1, int(mMinExcess.size()) - 1);
        const double earlier = i >= 0 ? mMinExcess[i] : 1e300;
        return z / kSoundSpeedMS + std::min(earlier, fitArrival - z / kSoundSpeedMS);
    }

private:
    double mLogLo = 0, mStep = 1;
    std::vector<double> mMinExcess;
};

CoreValues coreValues(BlastDataset dataset, BurstType burst, double z)
{
    CoreValues v = coreValuesRaw(dataset, burst, z);
    if (dataset == BlastDataset::KingeryBulmash) {
        static const ArrivalEnvelope freeAir(BlastDataset::KingeryBulmash, BurstType::FreeAir);
        static const ArrivalEnvelope surface(BlastDataset::KingeryBulmash, BurstType::Surface);
        v.ta = (burst == BurstType::FreeAir ? freeAir : surface).arrival(z, v.ta);
    }
    return v;
}

}  // namespace

double friedlanderImpulseFraction(double b)
{
    if (std::abs(b) < 1e-3) {
        // k(b) = sum_n (-b)^n / (n+2)!: avoids the cancellation of the closed form near 0.
        return 0.5 - b / 6.0 + b * b / 24.0 - b * b * b / 120.0 + b * b * b * b / 720.0;
    }
    return 1.0 / b - (1.0 - std::exp(-b)) / (b * b);
}

double solveDecayCoefficient(double impulseFraction)
{
    // k(b) falls monotonically from +inf (b -> -inf) to 0 (b -> +inf): bisection always brackets.
    double lo = -60.0, hi = 500.0;
    if (!(impulseFraction > 0.0)) return hi;
    if (impulseFraction >= friedlanderImpulseFraction(lo)) return lo;
    if (impulseFraction <= friedlanderImpulseFraction(hi)) return hi;
    for (int i = 0; i < 200 && hi - lo > 1e-13 * std::max(1.0, std::abs(lo)); ++i) {
        const double mid = 0.5 * (lo + hi);
        if (friedlanderImpulseFraction(mid) > impulseFraction)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

BlastParameters scaledBlastDirect(BlastDataset dataset, BurstType burst, double z)
{
    const ZRange range = fittedRange(dataset, burst);
    BlastParameters out;
    CoreValues v;
    if (z < range.lo) {
        // Inside the fireball region the fits do not apply: hold their near-end values.
        v = coreValues(dataset, burst, range.lo);
        v.ta *= z / range.lo;
        out.status = RangeStatus::ClampedNear;
    } else if (z > range.hi) {
        // Far field: continue Ps and Is as power laws with the slope at the fit's end (Ps slope
        // kept within [-1.45, -1], blast-data.md §5), T+ constant, the front at sound speed.
        const double zh = range.hi, zi = range.hi * 0.98;
        const CoreValues end = coreValues(dataset, burst, zh);
        const CoreValues inner = coreValues(dataset, burst, zi);
        const double lnRatio = std::log(z / zh), lnStep = std::log(zh / zi);
        const double psSlope = std::clamp(std::log(end.ps / inner.ps) / lnStep, -1.45, -1.0);
        const double isSlope = std::min(std::log(end.is / inner.is) / lnStep, -1.0);
        v = end;
        v.ps = end.ps * std::exp(psSlope * lnRatio);
        v.is = end.is * std::exp(isSlope * lnRatio);
        v.ir = end.ir * v.is / end.is;  // Ir/Is held at the fit's end value (near its acoustic limit, 2)
        v.ta = end.ta + (z - zh) / kSoundSpeedMS;
        v.pr = rankineHugoniotReflected(v.ps, kSeaLevelPressurePa);
        v.u = rankineHugoniotShockSpeed(v.ps, kSeaLevelPressurePa);
        out.status = RangeStatus::ExtrapolatedFar;
    } else {
        v = coreValues(dataset, burst, z);
    }
    out.scaledDistanceMKg13 = z;
    out.peakOverpressurePa = v.ps;
    out.arrivalTimeS = v.ta;
    out.positiveDurationS = v.td;
    out.positiveImpulsePaS = v.is;
    out.decayCoefficient = solveDecayCoefficient(v.is / (v.ps * v.td));
    out.negativePeakPa = granstromNegativePeakPa(z);
    out.negativeDurationS = kNegativeDurationScaledS;
    out.reflectedPressurePa = v.pr;
    out.reflectedImpulsePaS = v.ir;
    out.reflectedDecayCoefficient = solveDecayCoefficient(v.ir / (v.pr * v.td));
    out.shockSpeedMS = v.u;
    return out;
}

SachsScaling::SachsScaling(double tntKg, const Atmosphere& atmosphere)
{
    const double pRatio = atmosphere.pressurePa / kSeaLevelPressurePa;
    const double tRatio = kSeaLevelTemperatureK / atmosphere.temperatureK;
    lengthScale = std::cbrt(pRatio) / std::cbrt(tntKg);
    timeScale = std::cbrt(tntKg) / std::cbrt(pRatio) * std::sqrt(tRatio);
    pressureScale = pRatio;
    impulseScale = std::cbrt(tntKg) * std::cbrt(pRatio * pRatio) * std::sqrt(tRatio);
    speedScale = std::sqrt(atmosphere.temperatureK / kSeaLevelTemperatureK);
}

BlastParameters blastParameters(BlastDataset dataset, BurstType burst, double tntKg, double distanceM,
                                const Atmosphere& atmosphere)
{
    auto requirePositive = [](double value, const char* field) {
        if (!(value > 0.0) || !std::isfinite(value)) {
            std::ostringstream msg;
            msg << field << " must be a positive finite number, got " << value;
            throw InputError(msg.str());
        }
    };
    requirePositive(tntKg, "tnt_kg");
    requirePositive(distanceM, "distance_m");
    requirePositive(atmosphere.pressurePa, "ambient pressure_Pa");
    requirePositive(atmosphere.temperatureK, "ambient temperature_K");

    const SachsScaling sachs(tntKg, atmosphere);
    const double z = distanceM * sachs.lengthScale;
    const BlastParameters s = scaledBlastDirect(dataset, burst, z);

    BlastParameters p;
    p.scaledDistanceMKg13 = z;
    p.peakOverpressurePa = s.peakOverpressurePa * sachs.pressureScale;
    p.arrivalTimeS = s.arrivalTimeS * sachs.timeScale;
    p.positiveDurationS = s.positiveDurationS * sachs.timeScale;
    p.positiveImpulsePaS = s.positiveImpulsePaS * sachs.impulseScale;
    p.decayCoefficient = s.decayCoefficient;
    p.negativePeakPa = s.negativePeakPa * sachs.pressureScale;
    p.negativeDurationS = s.negativeDurationS * sachs.timeScale;
    p.reflectedPressurePa = s.reflectedPressurePa * sachs.pressureScale;
    p.reflectedImpulsePaS = s.reflectedImpulsePaS * sachs.impulseScale;
    p.reflectedDecayCoefficient = s.reflectedDecayCoefficient;
    p.shockSpeedMS = s.shockSpeedMS * sachs.speedScale;
    p.status = s.status;
    return p;
}

namespace blastdata {

ZRange fittedRange(BlastDataset dataset, BurstType burst)
{
    if (dataset == BlastDataset::KinneyGraham) return {0.05, 40.0};
    if (burst == BurstType::FreeAir) return {0.0531, 40.0};
    return {0.17 / kMetricToImperialZ, 100.0 / kMetricToImperialZ};
}

double rankineHugoniotShockSpeed(double ps, double p0) { return kSoundSpeedMS * std::sqrt(1.0 + 6.0 * ps / (7.0 * p0)); }

}  // namespace blastdata

}  // namespace spall
