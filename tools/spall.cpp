// spall: command-line front end. Only this file turns library errors into exit codes.
#include "BenchAccuracy.h"
#include "BenchCollisions.h"

#include <spall/blast/Blast.h>
#include <spall/core/Error.h>
#include <spall/io/History.h>
#include <spall/io/Png.h>
#include <spall/io/Scene.h>
#include <spall/io/VdbIo.h>
#include <spall/render/Render.h>
#include <spall/sim/Checkpoint.h>
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

/// An enum-valued option; a bad value is an error naming the option.
template <typename E>
E parseOption(const std::string& option, const std::string& value)
{
    try {
        return spall::parseEnum<E>(value);
    } catch (const spall::InputError& e) {
        throw spall::InputError(option + ": " + e.what());
    }
}

int runBlast(double tntKg, double distanceM, const std::string& burstName, const std::string& datasetName, bool json,
             const std::string& curvePath)
{
    const auto burst = parseOption<spall::BurstType>("--burst", burstName);
    const auto dataset = parseOption<spall::BlastDataset>("--dataset", datasetName);
    const spall::BlastParameters p = spall::blastParameters(dataset, burst, tntKg, distanceM);
    std::string warning;
    if (p.status == spall::RangeStatus::ClampedNear)
        warning = "scaled distance is nearer than the dataset's fits reach: values are held at the fits' near end";
    else if (p.status == spall::RangeStatus::ExtrapolatedFar)
        warning = "scaled distance is beyond the dataset's fits: values are extrapolated (power laws, sound speed)";
    if (!warning.empty()) std::cerr << "spall blast: warning: " << warning << "\n";

    if (!curvePath.empty()) {
        const bool png = curvePath.size() > 4 && curvePath.substr(curvePath.size() - 4) == ".png";
        const double end = p.arrivalTimeS + 1.2 * (p.positiveDurationS + p.negativeDurationS);
        const int samples = 2000;
        std::vector<double> times, pressures;
        for (int i = 0; i <= samples; ++i) {
            times.push_back(end * i / samples);
            pressures.push_back(spall::overpressureAt(p, times.back()));
        }
        if (png) {
            std::vector<double> ms(times.size()), kPa(pressures.size());
            for (size_t i = 0; i < times.size(); ++i) {
                ms[i] = times[i] * 1e3;
                kPa[i] = pressures[i] * 1e-3;
            }
            char title[160];
            std::snprintf(title, sizeof title, "%g kg TNT at %g m (Z %.3g)", tntKg, distanceM, p.scaledDistanceMKg13);
            spall::writePng(curvePath, spall::plotCurve(ms, kPa, "time after detonation (ms)", "overpressure (kPa)", title));
        } else {
            std::ofstream out(curvePath);
            if (!out) throw spall::IoError(curvePath + ": cannot write");
            out << "time_s,overpressure_Pa\n";
            for (size_t i = 0; i < times.size(); ++i) out << times[i] << "," << pressures[i] << "\n";
            if (!out) throw spall::IoError(curvePath + ": write failed");
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

int runInspect(const std::string& path, bool json, int frameArg, int64_t bodyArg)
{
    const spall::History h = spall::readHistory(path);
    const int frames = static_cast<int>(h.frameCount());
    if (frames == 0) throw spall::InputError(path + ": the history holds no frames");
    if (frameArg >= frames || frameArg < -1)
        throw spall::InputError(path + ": --frame " + std::to_string(frameArg) + " does not exist (frames 0.." + std::to_string(frames - 1) + ")");
    const int f = frameArg >= 0 ? frameArg : frames - 1;
    const int64_t begin = h.bodyOffset[f], end = h.bodyOffset[f + 1];

    // Fragment sizes of the frame, by decades of voxel count.
    const char* bucketNames[] = {"1", "2-9", "10-99", "100-999", "1000-9999", ">=10000"};
    int64_t buckets[6] = {0, 0, 0, 0, 0, 0};
    double mass = 0, largest = 0, fastest = 0;
    int64_t asleep = 0, anchored = 0;
    for (int64_t i = begin; i < end; ++i) {
        const int64_t v = h.bodyVoxelCount[i];
        buckets[std::min(5, static_cast<int>(std::floor(std::log10(double(v)))))]++;
        mass += h.bodyMassKg[i];
        largest = std::max(largest, h.bodyMassKg[i]);
        fastest = std::max(fastest, h.bodyLinearVelocityMS[i].norm());
        asleep += h.bodyAsleep[i];
        anchored += h.bodyAnchored[i];
    }
    double maxKe = 0;
    int64_t steps = 0, broken = 0;
    for (int i = 0; i < frames; ++i) {
        maxKe = std::max(maxKe, h.kineticEnergyJ[i]);
        steps += h.steps[i];
        broken += h.brokenLinks[i];
    }
    nlohmann::json j;
    j["file"] = path;
    j["run_complete"] = h.runComplete;
    j["frames"] = frames;
    j["duration_s"] = h.timeS.back();
    j["voxel_size_m"] = h.voxelSizeM;
    j["seed"] = h.seed;
    j["steps"] = steps;
    j["broken_links"] = broken;
    j["fracture_events"] = h.eventTimeS.size();
    j["kinetic_energy_max_J"] = maxKe;
    j["frame"] = {{"index", f},
                  {"time_s", h.timeS[f]},
                  {"bodies", end - begin},
                  {"voxels", h.voxelCount[f]},
                  {"mass_kg", mass},
                  {"largest_fragment_kg", largest},
                  {"fastest_fragment_m_s", fastest},
                  {"asleep", asleep},
                  {"anchored", anchored},
                  {"kinetic_energy_J", h.kineticEnergyJ[f]},
                  {"linear_momentum_kg_m_s", {h.linearMomentum[f].x(), h.linearMomentum[f].y(), h.linearMomentum[f].z()}},
                  {"dust_mass_kg", h.dustMassKg[f]}};
    nlohmann::json sizes = nlohmann::json::object();
    for (int b = 0; b < 6; ++b) sizes[bucketNames[b]] = buckets[b];
    j["frame"]["fragment_voxel_counts"] = sizes;
    if (bodyArg >= 0) {
        nlohmann::json track = nlohmann::json::array();
        for (int i = 0; i < frames; ++i)
            for (int64_t r = h.bodyOffset[i]; r < h.bodyOffset[i + 1]; ++r)
                if (h.bodyId[r] == bodyArg) {
                    const auto& p = h.bodyPositionM[r];
                    const auto& v = h.bodyLinearVelocityMS[r];
                    track.push_back({{"frame", i}, {"time_s", h.timeS[i]}, {"position_m", {p.x(), p.y(), p.z()}},
                                     {"speed_m_s", v.norm()}, {"voxels", h.bodyVoxelCount[r]}, {"asleep", h.bodyAsleep[r] != 0}});
                }
        if (track.empty()) throw spall::InputError(path + ": --body " + std::to_string(bodyArg) + " does not appear in any frame");
        j["body"] = {{"id", bodyArg}, {"track", track}};
    }
    if (json) {
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::printf("%s: %d frames over %.3f s (%s), voxel size %g m, seed %llu\n", path.c_str(), frames, h.timeS.back(),
                h.runComplete ? "complete" : "INCOMPLETE: the run was interrupted", h.voxelSizeM, (unsigned long long)h.seed);
    std::printf("  %lld steps, %lld links broken, %zu fracture events, peak kinetic energy %.4g J\n", (long long)steps,
                (long long)broken, h.eventTimeS.size(), maxKe);
    std::printf("frame %d (t = %.3f s): %lld bodies (%lld asleep, %lld anchored), %lld voxels, %.4g kg\n", f, h.timeS[f],
                (long long)(end - begin), (long long)asleep, (long long)anchored, (long long)h.voxelCount[f], mass);
    std::printf("  largest fragment %.4g kg, fastest %.3g m/s, kinetic energy %.4g J, dust %.4g kg\n", largest, fastest,
                h.kineticEnergyJ[f], h.dustMassKg[f]);
    std::printf("  linear momentum (%.4g, %.4g, %.4g) kg m/s\n", h.linearMomentum[f].x(), h.linearMomentum[f].y(), h.linearMomentum[f].z());
    std::printf("  fragments by voxel count:");
    for (int b = 0; b < 6; ++b)
        if (buckets[b]) std::printf("  %s: %lld", bucketNames[b], (long long)buckets[b]);
    std::printf("\n");
    if (j.contains("body")) {
        std::printf("body %lld:\n", (long long)bodyArg);
        for (const auto& row : j["body"]["track"])
            std::printf("  frame %4d  t %.3f s  position (%.3f, %.3f, %.3f) m  speed %.3f m/s%s\n", row["frame"].get<int>(),
                        row["time_s"].get<double>(), row["position_m"][0].get<double>(), row["position_m"][1].get<double>(),
                        row["position_m"][2].get<double>(), row["speed_m_s"].get<double>(), row["asleep"].get<bool>() ? "  asleep" : "");
    }
    return 0;
}

spall::RenderSettings parseSize(const std::string& size)
{
    spall::RenderSettings s;
    int w = 0, h = 0;
    char x = 0;
    std::stringstream ss(size);
    if (!(ss >> w >> x >> h) || x != 'x' || w < 16 || h < 16 || w > 16384 || h > 16384)
        throw spall::InputError("--size '" + size + "' is not WIDTHxHEIGHT (16..16384 pixels each)");
    s.width = w;
    s.height = h;
    return s;
}

int runRender(const std::string& outDir, int frame, bool all, bool sheet, std::string pictureDir, const std::string& size)
{
    const spall::RenderSettings settings = parseSize(size);
    const std::vector<std::string> paths = spall::listFramePaths(outDir);
    if (pictureDir.empty()) pictureDir = outDir;
    std::filesystem::create_directories(pictureDir);
    if (sheet) {
        const std::string path = (std::filesystem::path(pictureDir) / "sheet.png").string();
        const int n = spall::writeContactSheet(outDir, path, 9, settings);
        std::printf("contact sheet of %d frames: %s\n", n, path.c_str());
        return 0;
    }
    std::vector<std::string> selected;
    if (all) {
        selected = paths;
    } else if (frame >= 0) {
        const std::string path = spall::FrameWriter::framePath(outDir, frame);
        if (std::find(paths.begin(), paths.end(), path) == paths.end())
            throw spall::InputError(path + ": frame " + std::to_string(frame) + " does not exist (" + std::to_string(paths.size()) + " frames)");
        selected = {path};
    } else {
        selected = {paths.back()};
    }
    const spall::FrameGrids first = spall::readFrame(paths.front()), last = spall::readFrame(paths.back());
    const spall::Camera camera = spall::frameCamera({spall::fragmentsOf(first), spall::fragmentsOf(last)}, settings);
    for (const std::string& path : selected) {
        const spall::FrameGrids f = spall::readFrame(path);
        char name[32];
        std::snprintf(name, sizeof name, "frame.%04d.png", f.frame);
        const std::string out = (std::filesystem::path(pictureDir) / name).string();
        spall::writePng(out, spall::renderFragments(spall::fragmentsOf(f), camera, settings));
        std::printf("%s\n", out.c_str());
    }
    return 0;
}

std::atomic<bool> gStopRequested{false};

extern "C" void requestStop(int) { gStopRequested = true; }

int runRun(const std::string& scenePath, const std::string& outDir, bool resume, int threads, int64_t seed, int frames, bool quiet,
           bool preview)
{
    std::unique_ptr<tbb::global_control> threadLimit;
    if (threads > 0) threadLimit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    // Ctrl-C finishes the current frame, so everything written stays readable.
    std::signal(SIGINT, requestStop);
    std::signal(SIGTERM, requestStop);

    spall::RunOptions options;
    options.outputDirectory = outDir;
    options.maxFrames = frames;
    if (preview) options.previewPath = (std::filesystem::path(outDir) / "preview.png").string();
    const auto onFrame = [&, firstFrame = -1](const spall::RunProgress& p) mutable {
        if (firstFrame < 0) firstFrame = p.frame;
        if (!quiet) {
            const int width = 30;
            const int filled = p.frameCount > 0 ? width * (p.frame + 1) / p.frameCount : width;
            const double perFrame = p.elapsedS / (p.frame + 1 - firstFrame);
            const double left = perFrame * (p.frameCount - p.frame - 1);
            std::fprintf(stderr, "\r[%-*s] frame %d/%d  t=%.3f s  bodies %zu  steps %lld  %.0f s left ", width,
                         std::string(filled, '#').c_str(), p.frame + 1, p.frameCount, p.timeS, p.bodies,
                         static_cast<long long>(p.totalSteps), left);
            std::fflush(stderr);
        }
        return !gStopRequested.load();
    };
    spall::RunReport report;
    if (resume) {
        if (!quiet) std::fprintf(stderr, "spall run: resuming %s\n", outDir.c_str());
        report = spall::resumeRun(options, onFrame);
    } else {
        spall::Scene scene = scenePath.empty() ? spall::parseScene(spall::defaultSceneJson(), "<built-in default scene>", ".")
                                               : spall::loadScene(scenePath);
        if (seed >= 0) {
            scene.seed = static_cast<uint64_t>(seed);
            scene.fracture.seed = scene.seed;
        }
        if (!quiet) std::fprintf(stderr, "spall run: %s -> %s\n", scene.sourceName.c_str(), outDir.c_str());
        report = spall::runScene(scene, options, onFrame);
    }
    if (!quiet) std::fprintf(stderr, "\n");
    std::printf("%s: %d frames, %zu bodies at the end, %lld fracture events, %lld steps, %.1f s\n",
                report.complete ? "finished" : "interrupted", report.framesWritten, report.finalBodies,
                static_cast<long long>(report.fractureEvents), static_cast<long long>(report.totalSteps), report.wallTimeS);
    std::printf("output: %s/fragments.NNNN.vdb (one grid per fragment + density), %s/history.h5, %s/scene.json\n",
                outDir.c_str(), outDir.c_str(), outDir.c_str());
    std::printf("open: Blender: File > Import > OpenVDB (the sequence); Houdini: File SOP on fragments.$F4.vdb;\n"
                "      Python: h5py.File('%s/history.h5') (see docs/file-formats.md)\n", outDir.c_str());
    if (!report.complete) {
        if (std::filesystem::exists(std::filesystem::path(outDir) / spall::kCheckpointFileName))
            std::fprintf(stderr, "spall run: interrupted after %d frames; they are complete and readable; continue with: spall run --resume %s\n",
                         report.framesWritten, outDir.c_str());
        else
            std::fprintf(stderr, "spall run: interrupted after %d frames; they are complete and readable; no checkpoint "
                                 "(output.checkpoint_every_s is 0), so finishing means running the scene again\n",
                         report.framesWritten);
        return 130;
    }
    if (preview) std::printf("preview: %s\n", options.previewPath.c_str());
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
    blast->add_option("--curve", curve, "Write the pressure history: .csv, or .png for a plot");

    // run
    auto* run = app.add_subcommand("run", "Simulate a scene (default: the built-in wall demo) and write frames and history");
    std::string runScenePath, runOut = "out";
    int runThreads = 0, runFrames = -1;
    int64_t runSeed = -1;
    bool runQuiet = false, runNoPreview = false;
    run->add_option("scene", runScenePath, "Scene JSON (docs/scene-format.md); omit for the built-in default");
    run->add_option("-o,--output", runOut, "Output directory");
    run->add_option("--threads", runThreads, "Worker threads (0: all cores); output does not depend on it")->check(CLI::NonNegativeNumber);
    run->add_option("--seed", runSeed, "Override the scene's seed")->check(CLI::NonNegativeNumber);
    run->add_option("--frames", runFrames, "Stop after this many frames")->check(CLI::NonNegativeNumber);
    run->add_flag("--quiet", runQuiet, "No progress bar");
    run->add_flag("--no-preview", runNoPreview, "Do not render OUTDIR/preview.png");
    std::string runResume;
    auto* resumeOption = run->add_option("--resume", runResume, "Continue the interrupted run in this output directory from its checkpoint");
    resumeOption->excludes(run->get_option("scene"))->excludes("--seed")->excludes("--frames")->excludes("--output");

    // render
    auto* render = app.add_subcommand("render", "Render preview pictures (PNG) of a run's frames");
    std::string renderDir, renderOut, renderSize = "960x540";
    int renderFrame = -1;
    bool renderAll = false, renderSheet = false;
    render->add_option("outdir", renderDir, "A spall run's output directory")->required();
    render->add_option("--frame", renderFrame, "Frame number (default: the last)");
    render->add_flag("--all", renderAll, "Every frame");
    render->add_flag("--sheet", renderSheet, "A contact sheet of nine frames across the run");
    render->add_option("-o,--output", renderOut, "Where the pictures go (default: the output directory)");
    render->add_option("--size", renderSize, "WIDTHxHEIGHT in pixels");

    // inspect
    auto* inspect = app.add_subcommand("inspect", "Summarise a run's history.h5");
    std::string inspectPath;
    bool inspectJson = false;
    int inspectFrame = -1;
    int64_t inspectBody = -1;
    inspect->add_option("history", inspectPath, "OUTDIR/history.h5 (or OUTDIR)")->required();
    inspect->add_flag("--json", inspectJson, "JSON output");
    inspect->add_option("--frame", inspectFrame, "Frame to summarise (default: the last)");
    inspect->add_option("--body", inspectBody, "Follow one body through the run");

    // bench
    auto* bench = app.add_subcommand("bench", "Benchmarks that print tables (the micro-benchmarks are in spall_bench)");
    auto* benchCollisionsCmd = bench->add_subcommand("collisions", "Table 5-1: steps per second against boundary voxels, per method");
    bench->require_subcommand(1);
    bool benchJson = false;
    long benchMaxVoxels = 1'000'000;
    benchCollisionsCmd->add_flag("--json", benchJson, "One JSON row per method and size");
    benchCollisionsCmd->add_option("--max-boundary-voxels", benchMaxVoxels, "Largest size to run")->check(CLI::PositiveNumber);
    auto* benchAccuracyCmd = bench->add_subcommand("accuracy", "Error against a reference next to run time: CSV and log-log plots");
    std::string benchAccuracyOut = "accuracy";
    double benchSceneDuration = 0.5;
    benchAccuracyCmd->add_option("-o,--output", benchAccuracyOut, "Directory for accuracy.csv and the plots");
    benchAccuracyCmd->add_option("--scene-duration", benchSceneDuration, "Seconds of the default scene per variant (s)")
        ->check(CLI::PositiveNumber);

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
        if (*render) return runRender(renderDir, renderFrame, renderAll, renderSheet, renderOut, renderSize);
        if (*inspect) {
            std::string path = inspectPath;
            if (std::filesystem::is_directory(path)) path = (std::filesystem::path(path) / "history.h5").string();
            return runInspect(path, inspectJson, inspectFrame, inspectBody);
        }
        if (*run) {
            const bool resume = !runResume.empty();
            return runRun(runScenePath, resume ? runResume : runOut, resume, runThreads, runSeed, runFrames, runQuiet, !runNoPreview);
        }
        if (*blast) return runBlast(tnt, dist, burst, dataset, blastJson, curve);
        if (*benchCollisionsCmd) return spall::benchCollisions(benchJson, benchMaxVoxels);
        if (*benchAccuracyCmd) return spall::benchAccuracy(benchAccuracyOut, benchSceneDuration);
    } catch (const spall::InputError& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
