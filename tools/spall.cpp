// spall: command-line front end. Only this file turns library errors into exit codes.
#include <spall/blast/Blast.h>
#include <spall/core/Error.h>
#include <spall/io/Scene.h>
#include <spall/io/VdbIo.h>
#include <spall/sim/Run.h>
#include <spall/voxel/Voxelise.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace {

/// Percent progress on stderr, at most a few updates per second.
class ProgressPrinter : public spall::Interrupter {
public:
    ProgressPrinter(std::string label, bool quiet) : mLabel(std::move(label)), mQuiet(quiet) {}
    ~ProgressPrinter() override
    {
        if (mPrinted) std::fprintf(stderr, "\r%s done\n", mLabel.c_str());
    }
    bool wasInterrupted(int percent) override
    {
        if (mQuiet || percent < 0) return false;
        const auto now = std::chrono::steady_clock::now();
        if (mPrinted && now - mLast < std::chrono::milliseconds(250) && percent < 100) return false;
        mLast = now;
        mPrinted = true;
        std::fprintf(stderr, "\r%s %3d%%", mLabel.c_str(), percent);
        return false;
    }

private:
    std::string mLabel;
    bool mQuiet;
    bool mPrinted = false;
    std::chrono::steady_clock::time_point mLast;
};

spall::Primitive parsePrimitive(const std::string& spec)
{
    // box:X,Y,Z | sphere:R | cylinder:R,H (metres)
    const auto colon = spec.find(':');
    const std::string kind = spec.substr(0, colon);
    std::vector<double> v;
    if (colon != std::string::npos) {
        std::stringstream ss(spec.substr(colon + 1));
        std::string item;
        while (std::getline(ss, item, ',')) {
            try {
                v.push_back(std::stod(item));
            } catch (const std::exception&) {
                throw spall::InputError("primitive '" + spec + "': '" + item + "' is not a number");
            }
        }
    }
    spall::Primitive p;
    if (kind == "box" && v.size() == 3) {
        p.shape = spall::PrimitiveShape::Box;
        p.sizeM = {v[0], v[1], v[2]};
    } else if (kind == "sphere" && v.size() == 1) {
        p.shape = spall::PrimitiveShape::Sphere;
        p.sizeM = {v[0], v[0], v[0]};
    } else if (kind == "cylinder" && v.size() == 2) {
        p.shape = spall::PrimitiveShape::Cylinder;
        p.sizeM = {v[0], v[0], v[1]};
    } else {
        throw spall::InputError("primitive '" + spec + "' is not box:X,Y,Z, sphere:R or cylinder:R,H (metres)");
    }
    return p;
}

int runVoxelise(const std::string& input, const std::string& primitiveSpec, const std::string& output,
                double voxelSize, int64_t maxVoxels, bool quiet)
{
    spall::VoxeliseSettings settings;
    settings.voxelSizeM = voxelSize;
    settings.maxVoxels = maxVoxels;
    spall::VoxeliseResult result;
    std::string source;
    const auto start = std::chrono::steady_clock::now();
    if (!primitiveSpec.empty()) {
        source = primitiveSpec;
        result = spall::voxelisePrimitive(parsePrimitive(primitiveSpec), settings);
    } else {
        source = input;
        std::vector<std::string> notes;
        const spall::TriangleMesh mesh = spall::loadMesh(input, &notes);
        ProgressPrinter progress("voxelising " + input, quiet);
        result = spall::voxeliseMesh(mesh, settings, input, &progress);
        result.notes.insert(result.notes.begin(), notes.begin(), notes.end());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    spall::writeVoxelisedBody(output, *result.grid, voxelSize, source);

    const spall::MassProperties mp = spall::computeMassProperties(*result.grid, voxelSize, 1000.0);
    const openvdb::CoordBBox box = result.grid->evalActiveVoxelBoundingBox();
    for (const auto& note : result.notes) std::cerr << "spall voxelise: note: " << source << ": " << note << "\n";
    std::cout << "voxelised " << source << " at " << voxelSize << " m\n"
              << "  voxels:        " << result.voxelCount << "\n"
              << "  links:         " << spall::countLinks(*result.grid) << "\n"
              << "  volume:        " << mp.voxelCount * voxelSize * voxelSize * voxelSize << " m^3\n"
              << "  extent:        " << box.dim().x() * voxelSize << " x " << box.dim().y() * voxelSize << " x "
              << box.dim().z() * voxelSize << " m\n"
              << "  throughput:    " << (seconds > 0 ? result.voxelCount / seconds : 0.0) << " voxels/s\n"
              << "  written:       " << output << "\n";
    return 0;
}

int runBlast(double tntKg, double distanceM, const std::string& burstName, const std::string& datasetName, bool json,
             const std::string& curvePath)
{
    const spall::BurstType burst = spall::parseBurstType(burstName);
    const spall::BlastDataset dataset = spall::parseBlastDataset(datasetName);
    const spall::BlastParameters p = spall::blastParameters(dataset, burst, tntKg, distanceM);
    std::string warning;
    if (p.status == spall::RangeStatus::ClampedNear)
        warning = "scaled distance is nearer than the dataset's fits reach: values are held at the fits' near end";
    else if (p.status == spall::RangeStatus::ExtrapolatedFar)
        warning = "scaled distance is beyond the dataset's fits: values are extrapolated (power laws, sound speed)";
    if (!warning.empty()) std::cerr << "spall blast: warning: " << warning << "\n";

    if (!curvePath.empty()) {
        const bool png = curvePath.size() > 4 && curvePath.substr(curvePath.size() - 4) == ".png";
        if (png) throw spall::InputError("--curve: PNG plots are not available yet; write a .csv");
        std::ofstream out(curvePath);
        if (!out) throw spall::IoError(curvePath + ": cannot write");
        out << "time_s,overpressure_Pa\n";
        const double end = p.arrivalTimeS + 1.2 * (p.positiveDurationS + p.negativeDurationS);
        const int samples = 2000;
        for (int i = 0; i <= samples; ++i) {
            const double t = end * i / samples;
            out << t << "," << spall::overpressureAt(p, t) << "\n";
        }
    }
    if (json) {
        nlohmann::json j = {{"tnt_kg", tntKg},
                            {"distance_m", distanceM},
                            {"burst", burstName},
                            {"dataset", datasetName},
                            {"scaled_distance_m_kg13", p.scaledDistanceMKg13},
                            {"peak_overpressure_Pa", p.peakOverpressurePa},
                            {"arrival_time_s", p.arrivalTimeS},
                            {"positive_duration_s", p.positiveDurationS},
                            {"decay_coefficient", p.decayCoefficient},
                            {"positive_impulse_Pa_s", p.positiveImpulsePaS},
                            {"negative_peak_Pa", p.negativePeakPa},
                            {"negative_duration_s", p.negativeDurationS},
                            {"reflected_pressure_Pa", p.reflectedPressurePa},
                            {"shock_speed_m_s", p.shockSpeedMS}};
        if (!warning.empty()) j["warning"] = warning;
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::printf("%g kg TNT, %s burst, at %g m (%s)\n", tntKg, burstName.c_str(), distanceM, datasetName.c_str());
    std::printf("  scaled distance       %12.5g m/kg^(1/3)\n", p.scaledDistanceMKg13);
    std::printf("  peak overpressure     %12.5g kPa\n", p.peakOverpressurePa * 1e-3);
    std::printf("  arrival time          %12.5g ms\n", p.arrivalTimeS * 1e3);
    std::printf("  positive duration     %12.5g ms\n", p.positiveDurationS * 1e3);
    std::printf("  positive impulse      %12.5g kPa ms\n", p.positiveImpulsePaS);
    std::printf("  decay coefficient b   %12.5g\n", p.decayCoefficient);
    std::printf("  negative peak         %12.5g kPa\n", p.negativePeakPa * 1e-3);
    std::printf("  negative duration     %12.5g ms\n", p.negativeDurationS * 1e3);
    std::printf("  reflected pressure    %12.5g kPa\n", p.reflectedPressurePa * 1e-3);
    std::printf("  shock speed           %12.5g m/s\n", p.shockSpeedMS);
    return 0;
}

std::atomic<bool> gStopRequested{false};

extern "C" void requestStop(int) { gStopRequested = true; }

int runRun(const std::string& scenePath, const std::string& outDir, int threads, int64_t seed, int frames, bool quiet)
{
    spall::Scene scene = scenePath.empty() ? spall::parseScene(spall::defaultSceneJson(), "<built-in default scene>", ".")
                                           : spall::loadScene(scenePath);
    if (seed >= 0) {
        scene.seed = static_cast<uint64_t>(seed);
        scene.fracture.seed = scene.seed;
    }
    std::unique_ptr<tbb::global_control> threadLimit;
    if (threads > 0) threadLimit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    // Ctrl-C finishes the current frame, so everything written stays readable.
    std::signal(SIGINT, requestStop);
    std::signal(SIGTERM, requestStop);

    spall::RunOptions options;
    options.outputDirectory = outDir;
    options.maxFrames = frames;
    if (!quiet) std::fprintf(stderr, "spall run: %s -> %s\n", scene.sourceName.c_str(), outDir.c_str());
    const spall::RunReport report = spall::runScene(scene, options, [&](const spall::RunProgress& p) {
        if (!quiet) {
            const int width = 30;
            const int filled = p.frameCount > 0 ? width * (p.frame + 1) / p.frameCount : width;
            const double perFrame = p.elapsedS / (p.frame + 1);
            const double left = perFrame * (p.frameCount - p.frame - 1);
            std::fprintf(stderr, "\r[%-*s] frame %d/%d  t=%.3f s  bodies %zu  steps %lld  %.0f s left ", width,
                         std::string(filled, '#').c_str(), p.frame + 1, p.frameCount, p.timeS, p.bodies,
                         static_cast<long long>(p.totalSteps), left);
            std::fflush(stderr);
        }
        return !gStopRequested.load();
    });
    if (!quiet) std::fprintf(stderr, "\n");
    std::printf("%s: %d frames, %zu bodies at the end, %lld fracture events, %lld steps, %.1f s\n",
                report.complete ? "finished" : "interrupted", report.framesWritten, report.finalBodies,
                static_cast<long long>(report.fractureEvents), static_cast<long long>(report.totalSteps), report.wallTimeS);
    std::printf("output: %s/fragments.NNNN.vdb (one grid per fragment + density), %s/history.h5, %s/scene.json\n",
                outDir.c_str(), outDir.c_str(), outDir.c_str());
    std::printf("open: Blender: File > Import > OpenVDB (the sequence); Houdini: File SOP on fragments.$F4.vdb;\n"
                "      Python: h5py.File('%s/history.h5') (see docs/file-formats.md)\n", outDir.c_str());
    if (!report.complete) {
        std::fprintf(stderr, "spall run: interrupted after %d frames; they are complete and readable\n", report.framesWritten);
        return 130;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    CLI::App app{"spall: volumetric debris from a physically based blast"};
    app.require_subcommand(1);

    // voxelise
    auto* vox = app.add_subcommand("voxelise", "Voxelise a mesh or a primitive into a solid .vdb body");
    vox->alias("voxelize");
    std::string voxInput, voxPrimitive, voxOutput;
    double voxSize = 0.05;
    int64_t voxMax = 200'000'000;
    bool voxQuiet = false;
    vox->add_option("input", voxInput, "Mesh file (OBJ, STL, PLY, OFF, glTF, ...)");
    vox->add_option("--primitive", voxPrimitive, "Instead of a mesh: box:X,Y,Z | sphere:R | cylinder:R,H (m)");
    vox->add_option("-o,--output", voxOutput, "Output .vdb")->required();
    vox->add_option("--voxel-size", voxSize, "Voxel edge (m)")->required();
    vox->add_option("--max-voxels", voxMax, "Refuse results with more voxels than this");
    vox->add_flag("--quiet", voxQuiet, "No progress on stderr");

    // blast
    auto* blast = app.add_subcommand("blast", "Print blast-wave parameters of a TNT charge at a distance");
    double tnt = 0, dist = 0;
    std::string burst = "free-air", dataset = "kingery-bulmash", curve;
    bool blastJson = false;
    blast->add_option("--tnt-kg", tnt, "Charge mass (kg TNT)")->required();
    blast->add_option("--distance-m", dist, "Distance from the charge (m)")->required();
    blast->add_option("--burst", burst, "free-air | surface");
    blast->add_option("--dataset", dataset, "kingery-bulmash | kinney-graham");
    blast->add_flag("--json", blastJson, "JSON with SI units in every key");
    blast->add_option("--curve", curve, "Write the pressure history (.csv)");

    // run
    auto* run = app.add_subcommand("run", "Simulate a scene (default: the built-in wall demo) and write frames and history");
    std::string runScenePath, runOut = "out";
    int runThreads = 0, runFrames = -1;
    int64_t runSeed = -1;
    bool runQuiet = false;
    run->add_option("scene", runScenePath, "Scene JSON (docs/scene-format.md); omit for the built-in default");
    run->add_option("-o,--output", runOut, "Output directory");
    run->add_option("--threads", runThreads, "Worker threads (0: all cores); output does not depend on it")->check(CLI::NonNegativeNumber);
    run->add_option("--seed", runSeed, "Override the scene's seed")->check(CLI::NonNegativeNumber);
    run->add_option("--frames", runFrames, "Stop after this many frames")->check(CLI::NonNegativeNumber);
    run->add_flag("--quiet", runQuiet, "No progress bar");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        if (*vox) {
            if (voxInput.empty() == voxPrimitive.empty())
                throw spall::InputError("give either a mesh file or --primitive, not both or neither");
            return runVoxelise(voxInput, voxPrimitive, voxOutput, voxSize, voxMax, voxQuiet);
        }
        if (*run) return runRun(runScenePath, runOut, runThreads, runSeed, runFrames, runQuiet);
        if (*blast) return runBlast(tnt, dist, burst, dataset, blastJson, curve);
    } catch (const spall::InputError& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
