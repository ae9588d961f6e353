// `spall run`: simulate a scene, or resume one, with progress and Ctrl-C handling.
#include "Commands.h"

#include <spall/core/Error.h>
#include <spall/scene/Scene.h>
#include <spall/sim/Checkpoint.h>
#include <spall/run/Run.h>
#include <spall/voxel/Voxelise.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

namespace {

/// A duration as a person reads it: 42 s, 7 min 03 s, 2 h 05 min.
std::string readableDuration(double seconds)
{
    const long long s = std::llround(std::max(0.0, seconds));
    char text[48];
    if (s < 60)
        std::snprintf(text, sizeof text, "%lld s", s);
    else if (s < 3600)
        std::snprintf(text, sizeof text, "%lld min %02lld s", s / 60, s % 60);
    else
        std::snprintf(text, sizeof text, "%lld h %02lld min", s / 3600, (s % 3600) / 60);
    return text;
}

/// Where the progress bar measures a pace from: the wall clock and the work done then, or
/// none yet (fromS < 0).
struct PaceStart {
    double fromS = -1.0;
    double work = 0.0;  ///< simulated seconds, or lattice particle-steps
};

/// What the progress bar says of the time to come. While lattices run (a simulated second of the
/// deformable phase costs hours where the flight after it costs seconds, so the pace in
/// simulated time says nothing of the rest): the most particle-steps they can still take at the
/// particle-steps per second since the phase began. After: the time left at the pace since.
std::string timeToCome(const spall::RunProgress& p, PaceStart& flight, PaceStart& phase)
{
    if (p.latticeParticles > 0) {
        flight.fromS = -1.0;
        if (phase.fromS < 0.0) phase = {p.elapsedS, double(p.latticeParticleSteps)};
        const double stepsPerS = (double(p.latticeParticleSteps) - phase.work) / (p.elapsedS - phase.fromS);
        const std::string particles = std::to_string(p.latticeParticles) + " particles";
        if (!(stepsPerS > 0.0)) return "deformable phase (" + particles + "), pace not yet known";
        return "deformable phase (" + particles + "): at most " + readableDuration(double(p.latticeParticleStepsLeftAtMost) / stepsPerS) + " left";
    }
    phase.fromS = -1.0;
    if (flight.fromS < 0.0) flight = {p.elapsedS, p.timeS};
    const double simulatedS = p.timeS - flight.work;
    if (simulatedS <= 0.0) return "pace not yet known";
    return readableDuration((p.elapsedS - flight.fromS) * (p.endTimeS - p.timeS) / simulatedS) + " left at this pace";
}

/// The progress callback: draws a progress bar by simulated time with the time spent and the time
/// to come (timeToCome), unless quiet, and says whether to go on (not after Ctrl-C or SIGTERM).
std::function<bool(const spall::RunProgress&)> progressBar(bool quiet)
{
    return [quiet, flight = PaceStart(), phase = PaceStart()](const spall::RunProgress& p) mutable {
        if (!quiet) {
            const int width = 30;
            const double done = p.endTimeS > 0.0 ? std::min(1.0, p.timeS / p.endTimeS) : 1.0;
            std::fprintf(stderr, "\r[%-*s] frame %d/%d%s  t=%.4f s  bodies %zu  steps %lld  %s spent, %-56s", width,
                         std::string(size_t(width * done), '#').c_str(), p.frame + 1, p.frameCount, p.frameWritten ? "" : " (computing)",
                         p.timeS, p.bodies, static_cast<long long>(p.totalSteps), readableDuration(p.elapsedS).c_str(),
                         timeToCome(p, flight, phase).c_str());
            std::fflush(stderr);
        }
        return !stopRequested();
    };
}

/// What was written and how to open it; after an interruption, how to go on.
void printRunSummary(const spall::RunReport& report, const std::string& outDir)
{
    std::printf("%s: %d frames, %zu bodies at the end, %lld fracture events, %lld steps, %.1f s\n",
                report.complete ? "finished" : "interrupted", report.framesWritten, report.finalBodies,
                static_cast<long long>(report.fractureEvents), static_cast<long long>(report.totalSteps), report.wallTimeS);
    std::printf("output: %s/fragments.NNNN.vdb (one grid per fragment + density), %s/history.h5, %s/scene.json\n",
                outDir.c_str(), outDir.c_str(), outDir.c_str());
    std::printf("open: Blender: File > Import > OpenVDB (the sequence); Houdini: File SOP on fragments.$F4.vdb;\n"
                "      Python: h5py.File('%s/history.h5') (see docs/file-formats.md)\n", outDir.c_str());
    if (report.complete) return;
    if (report.stepAbandoned)
        std::fprintf(stderr, "spall run: the step in progress took too long to wait for and was given up; --resume goes on from the "
                             "last checkpoint and writes again the frames after it\n");
    if (std::filesystem::exists(std::filesystem::path(outDir) / spall::kCheckpointFileName))
        std::fprintf(stderr, "spall run: interrupted after %d frames; they are complete and readable; continue with: spall run --resume %s\n",
                     report.framesWritten, outDir.c_str());
    else
        std::fprintf(stderr, "spall run: interrupted after %d frames; they are complete and readable; no checkpoint "
                             "(none written yet, or output.checkpoint_every_s is 0), so spall run --resume runs the scene again\n",
                     report.framesWritten);
}

/// What `spall run` was asked.
struct RunRequest {
    std::string scene, output = "out", resume;
    int threads = 0, frames = -1;
    int64_t seed = -1;
    bool quiet = false, noPreview = false, gltf = false, overwrite = false;
};

int runRun(const RunRequest& request)
{
    const bool resume = !request.resume.empty(), quiet = request.quiet, preview = !request.noPreview, gltf = request.gltf;
    const std::string& outDir = resume ? request.resume : request.output;
    const std::string& scenePath = request.scene;
    const int threads = request.threads;
    const int64_t seed = request.seed;
    std::unique_ptr<tbb::global_control> threadLimit;
    if (threads > 0) threadLimit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    // Ctrl-C finishes the current frame, so everything written stays readable.
    stopOnSignals();

    StopRequest stopRequest;
    spall::RunOptions options;
    options.outputDirectory = outDir;
    options.interrupter = &stopRequest;
    options.onNote = [](const std::string& note) { std::fprintf(stderr, "spall run: note: %s\n", note.c_str()); };
    options.maxFrames = request.frames;
    options.replaceEarlierRun = request.overwrite;
    if (preview) options.previewPath = (std::filesystem::path(outDir) / "preview.png").string();
    if (gltf) {
        options.gltfPath = defaultGlbPath(outDir);
        options.onGltfFrame = gltfProgress(quiet);
    }
    const auto onFrame = progressBar(quiet);
    spall::RunReport report;
    if (resume) {
        if (!quiet) std::fprintf(stderr, "spall run: resuming %s\n", outDir.c_str());
        report = spall::resumeRun(options, onFrame);
    } else {
        spall::Scene scene = scenePath.empty() ? spall::parseScene(spall::defaultSceneJson(), "<built-in default scene>", ".")
                                               : spall::loadScene(scenePath);
        if (seed >= 0) scene.seed = static_cast<uint64_t>(seed);
        if (!quiet) std::fprintf(stderr, "spall run: %s -> %s\n", scene.sourceName.c_str(), outDir.c_str());
        try {
            report = spall::runScene(scene, options, onFrame);
        } catch (const spall::VoxeliseInterrupted& e) {
            throw spall::VoxeliseInterrupted(std::string(e.what()) + "; no frame was written; start it again with: spall run --resume " + outDir);
        }
    }
    if (!quiet) std::fprintf(stderr, "\n");
    if (report.restartedFromScene)
        std::fprintf(stderr, "spall run: %s held no checkpoint yet, so the run started again from %s/scene.json; the frames "
                             "written before were rewritten (the run is deterministic: they came out the same)\n", outDir.c_str(), outDir.c_str());
    printRunSummary(report, outDir);
    if (!report.complete) return 130;
    if (preview) std::printf("preview: %s\n", options.previewPath.c_str());
    if (report.gltf) printGltfReport(options.gltfPath, *report.gltf);
    return 0;
}

}  // namespace

void addRunCommand(CLI::App& app, CommandAction& action)
{
    auto o = std::make_shared<RunRequest>();
    auto* sub = app.add_subcommand("run", "Simulate a scene (default: the built-in wall demo) and write frames and history");
    sub->add_option("scene", o->scene, "Scene JSON (docs/scene-format.md); omit for the built-in default");
    sub->add_option("-o,--output", o->output, "Output directory");
    sub->add_option("--threads", o->threads, "Worker threads (0: all cores); output does not depend on it")->check(CLI::NonNegativeNumber);
    sub->add_option("--seed", o->seed, "Override the scene's seed")->check(CLI::NonNegativeNumber);
    sub->add_option("--frames", o->frames, "Stop after this many frames")->check(CLI::NonNegativeNumber);
    sub->add_flag("--quiet", o->quiet, "No progress bar");
    sub->add_flag("--no-preview", o->noPreview, "Do not render OUTDIR/preview.png");
    sub->add_flag("--gltf", o->gltf, "When the run completes, write OUTDIR/debris.glb (as spall export gltf OUTDIR)");
    sub->add_flag("--overwrite", o->overwrite, "Replace an earlier run's output in OUTDIR (without it such a directory is refused)");
    sub->add_option("--resume", o->resume, "Continue the interrupted run in this output directory from its checkpoint")
        ->excludes(sub->get_option("scene"))
        ->excludes("--seed")
        ->excludes("--frames")
        ->excludes("--output")
        ->excludes("--overwrite");
    sub->callback([o, &action] {
        action = [o] { return runRun(*o); };
    });
}
