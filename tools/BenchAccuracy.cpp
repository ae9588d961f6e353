#include "BenchAccuracy.h"

#include <spall/blast/Blast.h>
#include <spall/dynamics/Integrate.h>
#include <spall/loads/BlastLoads.h>
#include <spall/fracture/Fracture.h>
#include <spall/output/Png.h>
#include <spall/scene/Scene.h>
#include <spall/sim/Simulation.h>
#include <spall/voxel/Voxelise.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>

namespace spall {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// One measurement: an error against a reference, and what it cost.
struct Row {
    std::string study, problem, variant;
    double parameter;  ///< the knob being turned (dt, nodes per decade, ...)
    std::string errorName;
    double error;
    double timeS;
};

Body voxelBox(int nx, int ny, int nz, double h, double density)
{
    VoxeliseSettings settings;
    settings.voxelSizeM = h;
    return makeBody(voxelisePrimitive({PrimitiveShape::Box, Eigen::Vector3d(nx, ny, nz) * h}, settings).grid, h, density);
}

const WrenchFunction kNoForce = [](double, const Eigen::Vector3d&, const Eigen::Quaterniond&, const Eigen::Vector3d&,
                                   const Eigen::Vector3d&) { return Wrench(); };

/// Integrators on closed-form problems, each at time steps halving from coarse to fine.
void integratorStudy(std::vector<Row>& rows)
{
    const Integrator integrators[] = {Integrator::ExplicitEuler, Integrator::SemiImplicitEuler, Integrator::RungeKutta4};
    for (Integrator integrator : integrators) {
        const std::string name = enumName(integrator);
        // Ballistic flight for 1 s: x(t) = x0 + v0 t + g t^2 / 2.
        for (int n = 15; n <= 3840; n *= 2) {
            Body b = voxelBox(2, 2, 2, 0.1, 1000.0);
            const Eigen::Vector3d g(0, 0, -9.81), v0(4, -2, 12);
            b.motion.positionM = Eigen::Vector3d::Zero();
            b.motion.linearVelocityMS = v0;
            const double m = b.mass.massKg, dt = 1.0 / n;
            const WrenchFunction gravity = [m, g](double, const Eigen::Vector3d&, const Eigen::Quaterniond&, const Eigen::Vector3d&,
                                                  const Eigen::Vector3d&) { return Wrench{m * g, Eigen::Vector3d::Zero()}; };
            const auto start = Clock::now();
            for (int i = 0; i < n; ++i) integrateBody(b, i * dt, dt, integrator, gravity);
            const double error = (b.motion.positionM - (v0 + 0.5 * g)).norm();
            rows.push_back({"integrator", "ballistic", name, dt, "position_error_m", error, secondsSince(start)});
        }
        // Torque-free asymmetric body spinning near its major axis for 2 s: energy is conserved.
        for (int n = 60; n <= 15360; n *= 2) {
            Body b = voxelBox(6, 4, 2, 0.1, 1000.0);
            b.motion.angularVelocityRadS = Eigen::Vector3d(0.5, 0.3, 6.0);
            const double e0 = kineticEnergyJ(b), dt = 2.0 / n;
            const auto start = Clock::now();
            for (int i = 0; i < n; ++i) integrateBody(b, i * dt, dt, integrator, kNoForce);
            rows.push_back({"integrator", "torque-free spin", name, dt, "relative_energy_error", std::abs(kineticEnergyJ(b) - e0) / e0,
                            secondsSince(start)});
        }
        // A Friedlander pulse (and negative phase) on a 0.1 m cube 25 m from 10 kg under the
        // paper's rule (side-on pressure on the face that looks at the charge, sampled at each
        // step's start): the velocity it leaves against the analytic impulse times the face area
        // over the mass. (Blast engineering's loads integrate each step exactly: no step error.)
        BlastSettings bs;
        const BlastField field({Charge{Eigen::Vector3d(-25, 0, 0), 10.0, 0.0, BurstType::FreeAir}}, bs);
        const BlastParameters p = field.tableParameters(0, 24.95);
        const double impulse = p.peakOverpressurePa * p.positiveDurationS * friedlanderImpulseFraction(p.decayCoefficient) -
                               9.0 / 16.0 * p.negativePeakPa * p.negativeDurationS;
        for (int n = 4; n <= 1024; n *= 2) {
            Body b = voxelBox(1, 1, 1, 0.1, 2000.0);
            b.motion.positionM = Eigen::Vector3d::Zero();
            const double expected = impulse * 0.01 / b.mass.massKg, dt = p.positiveDurationS / n;
            const auto start = Clock::now();
            // From the arrival, as the simulation steps (it lands on arrivals): the error is then
            // the integrator's, not that of a step straddling the jump at the front.
            for (int i = 0; i * dt < p.positiveDurationS + p.negativeDurationS + dt; ++i) {
                const double t = p.arrivalTimeS + i * dt;
                const auto windows = field.openWindows(t);
                const Wrench blast = BlastLoads(field, windows, LoadSettings{LoadModel::Paper}, StaticWorld()).stepWrench(b, t, dt);
                integrateBody(b, t, dt, integrator, [&](double, const Eigen::Vector3d&, const Eigen::Quaterniond&, const Eigen::Vector3d&,
                                                        const Eigen::Vector3d&) { return blast; });
            }
            rows.push_back({"integrator", "friedlander pulse", name, dt, "relative_velocity_error",
                            std::abs(b.motion.linearVelocityMS.x() - expected) / std::abs(expected), secondsSince(start)});
        }
    }
}

/// The blast table against the direct Kingery–Bulmash fits, and what a lookup costs.
void tableStudy(std::vector<Row>& rows)
{
    for (int nodes : {8, 16, 32, 64, 128, 256, 512}) {
        BlastSettings bs;
        bs.tableNodesPerDecade = nodes;
        const BlastField field({Charge{Eigen::Vector3d::Zero(), 1.0, 0.0, BurstType::FreeAir}}, bs);
        double worst = 0;
        std::vector<double> errors;
        for (double z = 0.2; z < 40.0; z *= 1.003) {
            const double direct = scaledBlastDirect(BlastDataset::KingeryBulmash, BurstType::FreeAir, z).peakOverpressurePa;
            errors.push_back(std::abs(field.tableParameters(0, z).peakOverpressurePa / direct - 1.0));
            worst = std::max(worst, errors.back());
        }
        std::sort(errors.begin(), errors.end());
        const auto windows = field.openWindows(0.02);
        double sum = 0;
        const int lookups = 2'000'000;
        const auto start = Clock::now();
        for (int i = 0; i < lookups; ++i) sum += field.sample(Eigen::Vector3d(1.0 + 20.0 * i / lookups, 0.1, 0.2), 0.02, windows).overpressurePa;
        const double perLookup = secondsSince(start) / lookups;  // unit: s per lookup
        volatile double sink = sum;  // keeps the lookups from being optimised away
        (void)sink;
        rows.push_back({"blast table", "peak overpressure", "max", double(nodes), "relative_error", worst, perLookup});
        rows.push_back({"blast table", "peak overpressure", "99th percentile", double(nodes), "relative_error",
                        errors[size_t(0.99 * (errors.size() - 1))], perLookup});
    }
}

/// Pressure at link midpoints (what spall loads) against pressure at voxel centres (half a voxel
/// off), while a front crosses a wall: how different, and how many break decisions change.
void midpointStudy(std::vector<Row>& rows)
{
    for (double h : {0.2, 0.1, 0.05}) {
        BlastSettings bs;
        const BlastField field({Charge{Eigen::Vector3d(0, -4, 0), 20.0, 0.0, BurstType::Surface}}, bs);
        const Material m = findMaterialPreset("brick-masonry");
        const int nx = int(std::lround(4.0 / h)), nz = int(std::lround(2.5 / h));
        double sumRelative = 0, worst = 0;
        int64_t links = 0, decisionsDiffer = 0;
        const auto start = Clock::now();
        for (int k = 0; k < 8; ++k) {
            // The front at 4.0 .. 4.7 m: inside the wall.
            const double t = field.tableParameters(0, 4.0 + 0.1 * k).arrivalTimeS + 1e-5;
            const PressureSnapshot pressure(field, t, 0.0);
            for (int i = 0; i < nx; ++i)
                for (int j = 0; j < nz; ++j) {
                    const Eigen::Vector3d centre(-2.0 + (i + 0.5) * h, 0.0, (j + 0.5) * h);
                    for (int axis : {0, 2}) {
                        const Eigen::Vector3d mid = centre + 0.5 * h * Eigen::Vector3d::Unit(axis);
                        const double pMid = pressure.sample(mid).overpressurePa, pCentre = pressure.sample(centre).overpressurePa;
                        if (pMid == 0 && pCentre == 0) continue;
                        const double relative = std::abs(pMid - pCentre) / std::max(std::abs(pMid), std::abs(pCentre));
                        sumRelative += relative;
                        worst = std::max(worst, relative);
                        const double limit = baseYieldLimit(m, 1, openvdb::Coord(i, 0, j), axis);
                        decisionsDiffer += (pMid >= limit) != (pCentre >= limit);
                        ++links;
                    }
                }
        }
        const double time = secondsSince(start);
        rows.push_back({"midpoint vs centre", "front crossing a wall", "mean", h, "relative_pressure_difference", sumRelative / links, time});
        rows.push_back({"midpoint vs centre", "front crossing a wall", "max", h, "relative_pressure_difference", worst, time});
        rows.push_back({"midpoint vs centre", "front crossing a wall", "break decisions", h, "fraction_that_differ",
                        double(decisionsDiffer) / double(links), time});
    }
}

/// What a user sees of a run, per frame.
struct SceneResult {
    double wallTimeS = 0;
    std::vector<std::vector<std::pair<double, Eigen::Vector3d>>> frames;  ///< (mass, centre of mass) per body, heaviest first
    double kineticEnergyJ = 0;
};

SceneResult runScene(const nlohmann::json& scene, double durationS)
{
    SceneResult r;
    const Scene s = parseScene(scene.dump(), "paper wall (accuracy study)", ".");
    const auto start = Clock::now();
    Simulation sim(s);
    for (int f = 0; f * (1.0 / s.frameRateHz) <= durationS + 1e-12; ++f) {
        sim.advanceTo(f / s.frameRateHz);
        std::vector<std::pair<double, Eigen::Vector3d>> bodies;
        for (const Body& b : sim.bodies()) bodies.push_back({b.mass.massKg, b.motion.positionM});
        std::stable_sort(bodies.begin(), bodies.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
        r.frames.push_back(std::move(bodies));
    }
    r.wallTimeS = secondsSince(start);
    for (const Body& b : sim.bodies()) r.kineticEnergyJ += kineticEnergyJ(b);
    return r;
}

/// Mass-weighted RMS distance of the fragments from the object's initial centre of mass.
double spreadM(const std::vector<std::pair<double, Eigen::Vector3d>>& bodies, const Eigen::Vector3d& origin)
{
    double mass = 0, sum = 0;
    for (const auto& [m, x] : bodies) {
        mass += m;
        sum += m * (x - origin).squaredNorm();
    }
    return std::sqrt(sum / mass);
}

/// L1 distance between the cumulative mass fractions over fragment mass (log bins): 0 when the
/// distributions agree, up to 2.
double massDistributionDistance(const std::vector<std::pair<double, Eigen::Vector3d>>& a, const std::vector<std::pair<double, Eigen::Vector3d>>& b)
{
    const auto cumulative = [](const std::vector<std::pair<double, Eigen::Vector3d>>& bodies) {
        std::vector<double> bins(40, 0.0);
        double total = 0;
        for (const auto& [m, x] : bodies) {
            const int bin = std::clamp(int(std::floor(4.0 * std::log10(m) + 8)), 0, 39);
            bins[bin] += m;
            total += m;
        }
        std::partial_sum(bins.begin(), bins.end(), bins.begin());
        for (double& v : bins) v /= total;
        return bins;
    };
    const auto ca = cumulative(a), cb = cumulative(b);
    double d = 0;
    for (size_t i = 0; i < ca.size(); ++i) d += std::abs(ca[i] - cb[i]) / 4.0;  // per decade
    return d;
}

void sceneStudy(std::vector<Row>& rows, double durationS)
{
    const nlohmann::json base = nlohmann::json::parse(paperWallSceneJson());
    struct Variant {
        std::string name;
        double voxelM, frontFraction, pulseFraction, maxStepS;
    };
    // The reference is four times finer than the default in every tolerance.
    const std::vector<Variant> variants = {
        {"reference", 0.1, 0.125, 1.0 / 128, 1.0 / 960},
        {"default", 0.1, 0.5, 1.0 / 32, 1.0 / 240},
        {"coarse x2", 0.1, 1.0, 1.0 / 16, 1.0 / 120},
        {"coarse x4", 0.1, 2.0, 1.0 / 8, 1.0 / 60},
        {"fine x2", 0.1, 0.25, 1.0 / 64, 1.0 / 480},
        {"voxels 0.2 m", 0.2, 0.5, 1.0 / 32, 1.0 / 240},
    };
    std::map<std::string, SceneResult> results;
    for (const Variant& v : variants) {
        nlohmann::json scene = base;
        scene["voxel_size_m"] = v.voxelM;
        scene["duration_s"] = durationS;
        scene["solver"] = {{"front_fraction_voxels", v.frontFraction}, {"pulse_fraction", v.pulseFraction}, {"max_time_step_s", v.maxStepS}};
        std::fprintf(stderr, "spall bench accuracy: paper wall, %s ...\n", v.name.c_str());
        results[v.name] = runScene(scene, durationS);
    }
    const SceneResult& ref = results["reference"];
    const Eigen::Vector3d origin(0.0, 0.0, 1.25);
    for (const Variant& v : variants) {
        if (v.name == "reference") continue;
        const SceneResult& r = results[v.name];
        const double param = v.frontFraction;
        const auto& last = r.frames.back();
        const auto& refLast = ref.frames.back();
        rows.push_back({"paper wall", "fragments", v.name, param, "relative_error",
                        std::abs(double(last.size()) - double(refLast.size())) / double(refLast.size()), r.wallTimeS});
        rows.push_back({"paper wall", "mass distribution", v.name, param, "cumulative_L1_distance", massDistributionDistance(last, refLast),
                        r.wallTimeS});
        rows.push_back({"paper wall", "kinetic energy", v.name, param, "relative_error",
                        std::abs(r.kineticEnergyJ - ref.kineticEnergyJ) / ref.kineticEnergyJ, r.wallTimeS});
        const double refSpread = spreadM(refLast, origin);
        rows.push_back({"paper wall", "debris spread", v.name, param, "relative_error", std::abs(spreadM(last, origin) - refSpread) / refSpread,
                        r.wallTimeS});
        // Paths of the five heaviest fragments (matched by rank), RMS over frames, per spread.
        double sum = 0;
        int count = 0;
        for (size_t f = 0; f < std::min(r.frames.size(), ref.frames.size()); ++f)
            for (size_t k = 0; k < std::min<size_t>({5, r.frames[f].size(), ref.frames[f].size()}); ++k) {
                sum += (r.frames[f][k].second - ref.frames[f][k].second).squaredNorm();
                ++count;
            }
        rows.push_back({"paper wall", "paths of the 5 heaviest", v.name, param, "rms_error_per_spread", std::sqrt(sum / count) / refSpread,
                        r.wallTimeS});
    }
    rows.push_back({"paper wall", "reference run", "reference", 0.125, "none", 0.0, ref.wallTimeS});
}

void writeCsv(const std::string& path, const std::vector<Row>& rows)
{
    std::ofstream out(path);
    out << "study,problem,variant,parameter,error_name,error,time_s\n";
    char line[512];
    for (const Row& r : rows) {
        std::snprintf(line, sizeof line, "%s,%s,%s,%.9g,%s,%.6g,%.6g\n", r.study.c_str(), r.problem.c_str(), r.variant.c_str(), r.parameter,
                      r.errorName.c_str(), r.error, r.timeS);
        out << line;
    }
    if (!out) throw IoError(path + ": cannot write");
}

/// One log-log plot of error against run time, a line per (problem, variant) of a study.
void plotStudy(const std::string& path, const std::vector<Row>& rows, const std::string& study, bool seriesByProblem,
               const std::string& title)
{
    std::vector<PlotSeries> series;
    std::map<std::string, size_t> index;
    for (const Row& r : rows) {
        if (r.study != study || r.errorName == "none") continue;
        const std::string key = seriesByProblem ? r.problem : r.variant + " " + r.problem;
        if (!index.count(key)) {
            index[key] = series.size();
            series.push_back({key, {}, {}});
        }
        series[index[key]].x.push_back(r.timeS);
        series[index[key]].y.push_back(r.error);
    }
    for (PlotSeries& s : series) {  // a line from the cheapest point to the dearest
        std::vector<size_t> order(s.x.size());
        std::iota(order.begin(), order.end(), size_t(0));
        std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return s.x[a] < s.x[b]; });
        PlotSeries sorted{s.name, {}, {}};
        for (size_t i : order) sorted.x.push_back(s.x[i]), sorted.y.push_back(s.y[i]);
        s = std::move(sorted);
    }
    writePng(path, plotSeries(series, "run time (s)", "error", title, spall::PlotScale::LogLog, 1000, 620));
}

}  // namespace

int benchAccuracy(const std::string& outputDirectory, double sceneDurationS)
{
    std::filesystem::create_directories(outputDirectory);
    std::vector<Row> rows;
    std::fprintf(stderr, "spall bench accuracy: integrators, blast table, link midpoints ...\n");
    integratorStudy(rows);
    tableStudy(rows);
    midpointStudy(rows);
    sceneStudy(rows, sceneDurationS);

    std::printf("%-20s %-24s %-20s %12s %-30s %12s %10s\n", "study", "problem", "variant", "parameter", "error", "value", "time_s");
    for (const Row& r : rows)
        std::printf("%-20s %-24s %-20s %12.6g %-30s %12.4g %10.4g\n", r.study.c_str(), r.problem.c_str(), r.variant.c_str(), r.parameter,
                    r.errorName.c_str(), r.error, r.timeS);
    // Observed orders of convergence of the integrators (slope of log error against log dt).
    std::printf("\nobserved order (finest halving):\n");
    std::map<std::string, std::vector<const Row*>> byCurve;
    for (const Row& r : rows)
        if (r.study == "integrator") byCurve[r.problem + " / " + r.variant].push_back(&r);
    for (const auto& [name, curve] : byCurve) {
        // The last pair whose errors are both above round-off.
        double order = NAN;
        for (size_t i = 1; i < curve.size(); ++i)
            if (curve[i]->error > 1e-12 && curve[i - 1]->error > 1e-12)
                order = std::log(curve[i - 1]->error / curve[i]->error) / std::log(curve[i - 1]->parameter / curve[i]->parameter);
        std::printf("  %-45s %s\n", name.c_str(), std::isnan(order) ? "exact to round-off" : std::to_string(order).c_str());
    }
    namespace fs = std::filesystem;
    const fs::path dir = outputDirectory;
    writeCsv((dir / "accuracy.csv").string(), rows);
    std::vector<Row> integrators;
    for (const Row& r : rows)
        if (r.study == "integrator") integrators.push_back(r);
    for (const char* problem : {"ballistic", "torque-free spin", "friedlander pulse"}) {
        std::vector<Row> selected;
        for (const Row& r : integrators)
            if (r.problem == problem) selected.push_back(r);
        std::string file = std::string("accuracy-integrators-") + problem + ".png";
        std::replace(file.begin(), file.end(), ' ', '-');
        plotStudy((dir / file).string(), selected, "integrator", false, std::string("integrators: ") + problem);
    }
    plotStudy((dir / "accuracy-blast-table.png").string(), rows, "blast table", false, "blast table against the direct fits");
    plotStudy((dir / "accuracy-default-scene.png").string(), rows, "paper wall", true, "paper wall against a 4x finer reference");
    std::printf("\nwrote %s/accuracy.csv and %s/accuracy-*.png\n", outputDirectory.c_str(), outputDirectory.c_str());
    return 0;
}

}  // namespace spall
