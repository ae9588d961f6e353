// debris.h5, debris.csv and the debris plots (layout: docs/debris.md).
#include <spall/analysis/Debris.h>

#include <spall/core/AtomicFile.h>
#include <spall/core/Error.h>
#include <spall/output/H5Out.h>
#include <spall/output/Png.h>

#include <cstdio>

namespace spall {

namespace {

template <typename T, typename Get>
std::vector<T> column(const std::vector<FragmentFlight>& fragments, Get get)
{
    std::vector<T> out;
    for (const FragmentFlight& f : fragments) out.push_back(static_cast<T>(get(f)));
    return out;
}

template <typename Get>
std::vector<double> vectors(const std::vector<FragmentFlight>& fragments, Get get)
{
    std::vector<double> out;
    for (const FragmentFlight& f : fragments) {
        const Eigen::Vector3d v = get(f);
        out.insert(out.end(), {v.x(), v.y(), v.z()});
    }
    return out;
}

void writeFragments(H5Out& h5, const std::vector<FragmentFlight>& fr)
{
    h5.group("/fragments");
    h5.write("/fragments/id", column<int64_t>(fr, [](auto& f) { return f.id; }));
    h5.write("/fragments/mass_kg", column<double>(fr, [](auto& f) { return f.massKg; }));
    h5.write("/fragments/anchored", column<int64_t>(fr, [](auto& f) { return f.anchored; }));
    h5.write("/fragments/stayed", column<int64_t>(fr, [](auto& f) { return f.stayed; }));
    h5.write("/fragments/launched", column<int64_t>(fr, [](auto& f) { return f.launched; }));
    h5.write("/fragments/launch_time_s", column<double>(fr, [](auto& f) { return f.launchTimeS; }));
    h5.write("/fragments/launch_position_m", vectors(fr, [](auto& f) { return f.launchPositionM; }), 3);
    h5.write("/fragments/launch_velocity_m_s", vectors(fr, [](auto& f) { return f.launchVelocityMS; }), 3);
    h5.write("/fragments/peak_kinetic_energy_J", column<double>(fr, [](auto& f) { return f.peakKineticEnergyJ; }));
    h5.write("/fragments/impacted", column<int64_t>(fr, [](auto& f) { return f.impacted; }));
    h5.write("/fragments/impact_time_s", column<double>(fr, [](auto& f) { return f.impactTimeS; }));
    h5.write("/fragments/impact_position_m", vectors(fr, [](auto& f) { return f.impactPositionM; }), 3);
    h5.write("/fragments/impact_kinetic_energy_J", column<double>(fr, [](auto& f) { return f.impactKineticEnergyJ; }));
    h5.write("/fragments/rest_position_m", vectors(fr, [](auto& f) { return f.restPositionM; }), 3);
    h5.write("/fragments/throw_distance_m", column<double>(fr, [](auto& f) { return f.throwDistanceM; }));
    h5.write("/fragments/hazardous", column<int64_t>(fr, [](auto& f) { return f.hazardous; }));
}

void writeRings(H5Out& h5, const std::vector<DebrisRing>& rings)
{
    h5.group("/rings");
    std::vector<double> inner, outer, mass, density, hazardousDensity;
    std::vector<int64_t> count, hazardous, sectorCount, sectorHazardous;
    for (const DebrisRing& r : rings) {
        inner.push_back(r.innerM);
        outer.push_back(r.outerM);
        count.push_back(r.fragments);
        mass.push_back(r.massKg);
        hazardous.push_back(r.hazardous);
        density.push_back(r.fragmentDensityPerM2());
        hazardousDensity.push_back(r.hazardousDensityPerM2());
        sectorCount.insert(sectorCount.end(), r.sectorFragments.begin(), r.sectorFragments.end());
        sectorHazardous.insert(sectorHazardous.end(), r.sectorHazardous.begin(), r.sectorHazardous.end());
    }
    const size_t sectors = rings.empty() ? 1 : rings.front().sectorFragments.size();
    h5.write("/rings/inner_radius_m", inner);
    h5.write("/rings/outer_radius_m", outer);
    h5.write("/rings/fragments", count);
    h5.write("/rings/mass_kg", mass);
    h5.write("/rings/hazardous", hazardous);
    h5.write("/rings/fragment_density_per_m2", density);
    h5.write("/rings/hazardous_density_per_m2", hazardousDensity);
    h5.write("/rings/sector_fragments", sectorCount, sectors);
    h5.write("/rings/sector_hazardous", sectorHazardous, sectors);
}

void writeH5(H5Out& h5, const DebrisReport& report)
{
    h5.attribute("format_version", int64_t{1});
    h5.attribute("origin_x_m", report.originM.x());
    h5.attribute("origin_y_m", report.originM.y());
    h5.attribute("origin_z_m", report.originM.z());
    h5.attribute("hazardous_energy_J", report.settings.hazardousEnergyJ);
    h5.attribute("hazardous_area_m2", report.settings.hazardousAreaM2);
    h5.attribute("launch_speed_m_s", report.settings.launchSpeedMS);
    h5.attribute("stay_distance_m", report.settings.stayDistanceM);
    h5.attribute("max_throw_distance_m", report.maxThrowDistanceM);
    h5.attribute("median_throw_distance_m", report.medianThrowDistanceM);
    h5.attribute("mass_median_throw_distance_m", report.massMedianThrowDistanceM);
    h5.attribute("hazardous_fragment_distance_m", report.hazardousFragmentDistanceM);
    h5.attribute("worst_sector_hazardous_fragment_distance_m", report.worstSectorHazardousFragmentDistanceM);
    h5.attribute("weibull_fragments", report.massFit.fragments);
    h5.attribute("weibull_shape", report.massFit.shape);
    h5.attribute("weibull_scale_kg", report.massFit.scaleKg);
    h5.attribute("weibull_r_squared", report.massFit.rSquared);
    writeFragments(h5, report.fragments);
    writeRings(h5, report.rings);
}

void writeCsv(std::ostream& out, const DebrisReport& report)
{
    out << "id,mass_kg,anchored,stayed,launched,launch_time_s,launch_speed_m_s,peak_kinetic_energy_J,impacted,impact_time_s,"
           "impact_kinetic_energy_J,impact_x_m,impact_y_m,rest_x_m,rest_y_m,rest_z_m,throw_distance_m,hazardous\n";
    char line[512];
    for (const FragmentFlight& f : report.fragments) {
        std::snprintf(line, sizeof line, "%lld,%.9g,%d,%d,%d,%.9g,%.9g,%.9g,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d\n",
                      static_cast<long long>(f.id), f.massKg, f.anchored, f.stayed, f.launched, f.launchTimeS, f.launchVelocityMS.norm(),
                      f.peakKineticEnergyJ, f.impacted, f.impactTimeS, f.impactKineticEnergyJ, f.impactPositionM.x(), f.impactPositionM.y(),
                      f.restPositionM.x(), f.restPositionM.y(), f.restPositionM.z(), f.throwDistanceM, f.hazardous);
        out << line;
    }
}

std::string fixed(double value, int digits = 1)
{
    char s[64];
    std::snprintf(s, sizeof s, "%.*f", digits, value);
    return s;
}

Image throwPlot(const DebrisReport& report)
{
    std::vector<std::pair<double, double>> pieces;
    double totalMass = 0;
    for (const FragmentFlight& f : report.fragments)
        if (!f.stayed) {
            pieces.push_back({f.throwDistanceM, f.massKg});
            totalMass += f.massKg;
        }
    std::sort(pieces.begin(), pieces.end());
    PlotSeries count{"fragments", {}, {}}, mass{"mass", {}, {}};
    double massBeyond = totalMass;
    for (size_t i = 0; i < pieces.size(); ++i) {
        count.x.push_back(pieces[i].first);
        count.y.push_back(double(pieces.size() - i) / pieces.size());
        mass.x.push_back(pieces[i].first);
        mass.y.push_back(massBeyond / totalMass);
        massBeyond -= pieces[i].second;
    }
    const std::string title = "max " + fixed(report.maxThrowDistanceM) + " m  median " + fixed(report.medianThrowDistanceM) + " m  by mass " +
                              fixed(report.massMedianThrowDistanceM) + " m";
    return plotSeries({count, mass}, "resting distance from the charges (m)", "fraction beyond", title, PlotScale::Linear);
}

Image densityPlot(const DebrisReport& report)
{
    PlotSeries all{"all per m2", {}, {}}, hazardous{"hazardous per m2", {}, {}}, worst{"hazardous worst sector", {}, {}},
        limit{"1 per " + fixed(report.settings.hazardousAreaM2) + " m2", {}, {}};
    for (const DebrisRing& r : report.rings) {
        const double mid = 0.5 * (r.innerM + r.outerM);
        all.x.push_back(mid);
        all.y.push_back(r.fragmentDensityPerM2());
        hazardous.x.push_back(mid);
        hazardous.y.push_back(r.hazardousDensityPerM2());
        worst.x.push_back(mid);
        worst.y.push_back(r.worstSectorHazardousDensityPerM2());
    }
    if (!report.rings.empty()) limit = {limit.name, {0.0, report.rings.back().outerM}, {1 / report.settings.hazardousAreaM2, 1 / report.settings.hazardousAreaM2}};
    std::string title = "hazardous fragment distance " + fixed(report.hazardousFragmentDistanceM) + " m  (sector " +
                        fixed(report.worstSectorHazardousFragmentDistanceM) + " m)";
    if (report.hazardousCount() == 0)
        // The plot's font has no j: the hazard energy in newton metres.
        title = "no hazardous fragments: every impact below " + fixed(report.settings.hazardousEnergyJ, 0) + " newton metres";
    else if (report.worstSectorHazardousFragmentDistanceM == 0)
        title = "hazardous fragments nowhere denser than 1 per " + fixed(report.settings.hazardousAreaM2) + " m2";
    // Densities span decades and the limit is far below the densest rings: a log axis shows both.
    return plotSeries({all, hazardous, worst, limit}, "ring (m)", "per m2", title, PlotScale::LogY);
}

Image massPlot(const DebrisReport& report)
{
    std::vector<double> masses;
    for (const FragmentFlight& f : report.fragments)
        if (!f.stayed) masses.push_back(f.massKg);
    std::sort(masses.begin(), masses.end(), std::greater<>());
    PlotSeries counted{"fragments this heavy or more", {}, {}}, fitted{"weibull fit", {}, {}};
    for (size_t i = 0; i < masses.size(); ++i) {
        counted.x.push_back(masses[i]);
        counted.y.push_back(double(i + 1));
    }
    const WeibullMassFit& fit = report.massFit;
    // The fit down to half a fragment: below that it says nothing a count can show.
    if (fit.fragments > 0)
        for (double m : masses) {
            const double expected = fit.fragments * std::exp(-std::pow(m / fit.scaleKg, fit.shape));
            if (expected < 0.5) continue;
            fitted.x.push_back(m);
            fitted.y.push_back(expected);
        }
    const std::string title = fit.fragments > 0 ? "weibull shape " + fixed(fit.shape, 2) + " (mott 0.5)  scale " + fixed(fit.scaleKg, 3) +
                                                      " kg  r2 " + fixed(fit.rSquared, 3)
                                                : "no weibull fit: " + std::to_string(masses.size()) + " thrown fragments, it needs 3 masses";
    return plotSeries({counted, fitted}, "mass (kg)", "count", title, PlotScale::LogLog);
}

}  // namespace

void writeDebrisReport(const std::string& outDir, const DebrisReport& report)
{
    writeH5FileAtomically(outDir + "/debris.h5", [&](H5Out& h5) { writeH5(h5, report); });
    writeFileAtomically(outDir + "/debris.csv", [&](std::ostream& out) { writeCsv(out, report); });
    writePng(outDir + "/debris_throw.png", throwPlot(report));
    writePng(outDir + "/debris_density.png", densityPlot(report));
    writePng(outDir + "/debris_mass.png", massPlot(report));
}

}  // namespace spall
