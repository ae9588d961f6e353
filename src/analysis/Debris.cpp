#include <spall/analysis/Debris.h>

#include <spall/core/Error.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace spall {

namespace {

constexpr double kStandardGravityMS2 = 9.80665;

/// Each frame's rows by body id.
using FrameIndex = std::vector<std::unordered_map<int64_t, size_t>>;

FrameIndex indexFrames(const History& h)
{
    FrameIndex index(h.frameCount());
    for (size_t f = 0; f < index.size(); ++f)
        for (int64_t row = h.bodyOffset[f]; row < h.bodyOffset[f + 1]; ++row) index[f][h.bodyId[row]] = static_cast<size_t>(row);
    return index;
}

/// A fragment's row in every frame: its own, or its nearest ancestor's before it split off
/// (SIZE_MAX where neither exists).
std::vector<size_t> trackOf(int64_t id, const History& h, const FrameIndex& index, const std::unordered_map<int64_t, int64_t>& parentOf)
{
    std::vector<int64_t> lineage;
    for (int64_t at = id; at >= 0 && lineage.size() < 100000;) {
        lineage.push_back(at);
        const auto parent = parentOf.find(at);
        at = parent == parentOf.end() ? -1 : parent->second;
    }
    std::vector<size_t> rows(h.frameCount(), SIZE_MAX);
    for (size_t f = 0; f < rows.size(); ++f)
        for (int64_t body : lineage) {
            const auto row = index[f].find(body);
            if (row == index[f].end()) continue;
            rows[f] = row->second;
            break;
        }
    return rows;
}

/// The body's row in the first frame it appears in.
size_t birthRow(int64_t id, const FrameIndex& index)
{
    for (const auto& frame : index) {
        const auto row = frame.find(id);
        if (row != frame.end()) return row->second;
    }
    throw InputError("body " + std::to_string(id) + " is in no frame");
}

double horizontalDistanceM(const Eigen::Vector3d& p, const Eigen::Vector3d& origin)
{
    return (p - origin).head<2>().norm();
}

/// Launch, peak energy and first impact along a track: the impact is the first frame after the
/// launch in which a piece that was falling faster than half a frame of standard gravity has lost
/// more than half its downward speed (nothing in flight does that: drag cannot halve a fall
/// within a frame).
void followFlight(FragmentFlight& out, const History& h, const std::vector<size_t>& track, double launchSpeedMS)
{
    const auto energyJ = [&](size_t row) { return 0.5 * out.massKg * h.bodyLinearVelocityMS[row].squaredNorm(); };
    size_t launch = SIZE_MAX;
    for (size_t f = 0; f < track.size() && launch == SIZE_MAX; ++f)
        if (track[f] != SIZE_MAX && h.bodyLinearVelocityMS[track[f]].norm() >= launchSpeedMS) launch = f;
    if (launch == SIZE_MAX) return;
    out.launched = true;
    out.launchTimeS = h.timeS[launch];
    out.launchPositionM = h.bodyPositionM[track[launch]];
    out.launchVelocityMS = h.bodyLinearVelocityMS[track[launch]];
    out.peakKineticEnergyJ = energyJ(track[launch]);
    for (size_t f = launch + 1; f < track.size(); ++f) {
        const size_t before = track[f - 1], now = track[f];
        if (before == SIZE_MAX || now == SIZE_MAX) continue;
        const double fallingMS = h.bodyLinearVelocityMS[before].z();
        const double frameS = h.timeS[f] - h.timeS[f - 1];
        if (fallingMS < -0.5 * kStandardGravityMS2 * frameS && h.bodyLinearVelocityMS[now].z() > 0.5 * fallingMS) {
            out.impacted = true;
            out.impactTimeS = h.timeS[f];
            out.impactPositionM = h.bodyPositionM[now];
            out.impactKineticEnergyJ = energyJ(before);
            return;
        }
        out.peakKineticEnergyJ = std::max(out.peakKineticEnergyJ, energyJ(now));
    }
}

Eigen::Vector3d chargeCentreM(const History& h)
{
    if (h.chargeTntKg.empty()) throw InputError("history has no charges: nothing to measure throw distances from");
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double mass = 0;
    for (size_t c = 0; c < h.chargeTntKg.size(); ++c) {
        sum += h.chargeTntKg[c] * h.chargePositionM[c];
        mass += h.chargeTntKg[c];
    }
    return sum / mass;
}

/// The smallest of 1, 2 and 5 times a power of ten that is at least `rawM`.
double roundWidthM(double rawM)
{
    if (!(rawM > 0)) return 1.0;
    const double decade = std::pow(10.0, std::floor(std::log10(rawM)));
    for (double step : {1.0, 2.0, 5.0, 10.0})
        if (step * decade >= rawM * (1 - 1e-12)) return step * decade;
    return 10.0 * decade;
}

int sectorOf(const Eigen::Vector3d& p, const Eigen::Vector3d& origin, int sectors)
{
    const double width = 2 * M_PI / sectors;
    double angle = std::atan2(p.y() - origin.y(), p.x() - origin.x()) + 0.5 * width;
    if (angle < 0) angle += 2 * M_PI;
    return static_cast<int>(std::floor(angle / width)) % sectors;
}

std::vector<DebrisRing> countRings(const DebrisReport& report)
{
    double farthestM = 0;
    for (const FragmentFlight& f : report.fragments) {
        if (f.stayed) continue;
        farthestM = std::max(farthestM, f.throwDistanceM);
        if (f.hazardous) farthestM = std::max(farthestM, horizontalDistanceM(f.impactPositionM, report.originM));
    }
    const DebrisSettings& s = report.settings;
    const double width = s.ringWidthM > 0 ? s.ringWidthM : roundWidthM(farthestM / 20);
    const size_t count = static_cast<size_t>(std::floor(farthestM / width)) + 1;
    std::vector<DebrisRing> rings(count);
    for (size_t i = 0; i < count; ++i) {
        rings[i].innerM = i * width;
        rings[i].outerM = (i + 1) * width;
        rings[i].sectorFragments.assign(s.sectors, 0);
        rings[i].sectorHazardous.assign(s.sectors, 0);
    }
    const auto ringOf = [&](const Eigen::Vector3d& p) { return std::min(count - 1, size_t(horizontalDistanceM(p, report.originM) / width)); };
    for (const FragmentFlight& f : report.fragments) {
        if (f.stayed) continue;
        DebrisRing& rest = rings[ringOf(f.restPositionM)];
        ++rest.fragments;
        rest.massKg += f.massKg;
        ++rest.sectorFragments[sectorOf(f.restPositionM, report.originM, s.sectors)];
        if (!f.hazardous) continue;
        DebrisRing& hit = rings[ringOf(f.impactPositionM)];
        ++hit.hazardous;
        ++hit.sectorHazardous[sectorOf(f.impactPositionM, report.originM, s.sectors)];
    }
    return rings;
}

WeibullMassFit fitWeibull(std::vector<double> massesKg)
{
    WeibullMassFit fit;
    std::sort(massesKg.begin(), massesKg.end(), std::greater<>());
    const size_t n = massesKg.size();
    if (n < 3 || massesKg.front() == massesKg.back()) return fit;
    std::vector<double> x(n), y(n);
    for (size_t i = 0; i < n; ++i) {
        x[i] = std::log(massesKg[i]);
        y[i] = std::log(-std::log((i + 0.5) / n));  // Hazen's plotting position of the i-th largest
    }
    const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n, my = std::accumulate(y.begin(), y.end(), 0.0) / n;
    double sxx = 0, sxy = 0, syy = 0;
    for (size_t i = 0; i < n; ++i) {
        sxx += (x[i] - mx) * (x[i] - mx);
        sxy += (x[i] - mx) * (y[i] - my);
        syy += (y[i] - my) * (y[i] - my);
    }
    fit.fragments = static_cast<int64_t>(n);
    fit.shape = sxy / sxx;
    fit.scaleKg = std::exp(mx - my / fit.shape);
    fit.rSquared = sxy * sxy / (sxx * syy);
    return fit;
}

/// Distance below which `fraction` of the weights lie, the fragments sorted by distance.
double weightedQuantileM(std::vector<std::pair<double, double>> distanceAndWeight, double fraction)
{
    if (distanceAndWeight.empty()) return 0;
    std::sort(distanceAndWeight.begin(), distanceAndWeight.end());
    double total = 0;
    for (const auto& [d, w] : distanceAndWeight) total += w;
    double sum = 0;
    for (const auto& [d, w] : distanceAndWeight)
        if ((sum += w) >= fraction * total) return d;
    return distanceAndWeight.back().first;
}

void summarise(DebrisReport& report)
{
    std::vector<std::pair<double, double>> byCount, byMass;
    std::vector<double> masses;
    for (const FragmentFlight& f : report.fragments) {
        if (f.stayed) continue;
        report.maxThrowDistanceM = std::max(report.maxThrowDistanceM, f.throwDistanceM);
        byCount.push_back({f.throwDistanceM, 1.0});
        byMass.push_back({f.throwDistanceM, f.massKg});
        masses.push_back(f.massKg);
    }
    report.medianThrowDistanceM = weightedQuantileM(byCount, 0.5);
    report.massMedianThrowDistanceM = weightedQuantileM(byMass, 0.5);
    report.rings = countRings(report);
    const double limit = 1.0 / report.settings.hazardousAreaM2;
    for (const DebrisRing& ring : report.rings) {
        if (ring.hazardousDensityPerM2() >= limit) report.hazardousFragmentDistanceM = ring.outerM;
        if (ring.worstSectorHazardousDensityPerM2() >= limit) report.worstSectorHazardousFragmentDistanceM = ring.outerM;
    }
    report.massFit = fitWeibull(masses);
}

}  // namespace

double DebrisRing::areaM2() const { return M_PI * (outerM * outerM - innerM * innerM); }

double DebrisRing::worstSectorHazardousDensityPerM2() const
{
    const int64_t worst = sectorHazardous.empty() ? 0 : *std::max_element(sectorHazardous.begin(), sectorHazardous.end());
    return worst / (areaM2() / static_cast<double>(std::max<size_t>(1, sectorHazardous.size())));
}

int64_t DebrisReport::debrisCount() const
{
    return std::count_if(fragments.begin(), fragments.end(), [](const FragmentFlight& f) { return !f.stayed; });
}

int64_t DebrisReport::hazardousCount() const
{
    return std::count_if(fragments.begin(), fragments.end(), [](const FragmentFlight& f) { return f.hazardous; });
}

DebrisReport analyseDebris(const History& h, const DebrisSettings& settings)
{
    if (h.frameCount() == 0) throw InputError("history has no frames: nothing to analyse");
    DebrisReport report;
    report.settings = settings;
    report.originM = chargeCentreM(h);
    const FrameIndex index = indexFrames(h);
    std::unordered_map<int64_t, int64_t> parentOf;
    for (size_t row = 0; row < h.bodyId.size(); ++row) parentOf[h.bodyId[row]] = h.bodyParentId[row];
    const size_t last = h.frameCount() - 1;
    for (int64_t row = h.bodyOffset[last]; row < h.bodyOffset[last + 1]; ++row) {
        FragmentFlight f;
        f.id = h.bodyId[row];
        f.massKg = h.bodyMassKg[row];
        f.anchored = h.bodyAnchored[row] != 0;
        f.restPositionM = h.bodyPositionM[row];
        f.throwDistanceM = horizontalDistanceM(f.restPositionM, report.originM);
        f.stayed = f.anchored || horizontalDistanceM(f.restPositionM, h.bodyPositionM[birthRow(f.id, index)]) < settings.stayDistanceM;
        if (!f.anchored) followFlight(f, h, trackOf(f.id, h, index, parentOf), settings.launchSpeedMS);
        f.hazardous = !f.stayed && f.impacted && f.impactKineticEnergyJ >= settings.hazardousEnergyJ;
        report.fragments.push_back(f);
    }
    std::sort(report.fragments.begin(), report.fragments.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
    summarise(report);
    return report;
}

}  // namespace spall
