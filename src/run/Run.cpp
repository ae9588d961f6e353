#include <spall/run/Run.h>

#include <spall/core/AtomicFile.h>
#include <spall/output/History.h>
#include <spall/run/FrameSink.h>
#include <spall/sim/Checkpoint.h>
#include <spall/sim/Simulation.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace spall {

namespace {

/// The sinks the scene and the options ask for, in the order they write: frames, history,
/// preview, glTF (which meshes the frames once the run completes).
std::vector<std::unique_ptr<FrameSink>> frameSinks(const Simulation& sim, const RunOptions& options, int frameCount,
                                                   std::unique_ptr<HistoryWriter> history, std::optional<GltfExportReport>& gltf)
{
    const OutputSettings& output = sim.scene().output;
    std::vector<std::unique_ptr<FrameSink>> sinks;
    if (output.vdb) sinks.push_back(makeVdbSink(options.outputDirectory, output));
    if (history) sinks.push_back(makeHistorySink(std::move(history), sim));
    if (!options.previewPath.empty() && options.previewFrames > 0)
        sinks.push_back(makePreviewSink(options.previewPath, options.previewFrames, frameCount, sim.scene(), options.outputDirectory));
    if (!options.gltfPath.empty()) sinks.push_back(makeGltfSink(options.outputDirectory, options.gltfPath, options.onGltfFrame, gltf));
    return sinks;
}

/// The particles of the simulation's lattices in the deformable phase.
size_t latticeParticles(const Simulation& sim)
{
    size_t particles = 0;
    for (const DeformableBody& d : sim.state().deformable.lattices) particles += d.lattice.particleCount();
    return particles;
}

/// Where a run stands at simulated time `timeS` within (or at the end of) `frame`, for the
/// progress callback.
RunProgress progressOf(const Simulation& sim, int frame, int frameCount, double timeS, int64_t steps, double elapsedS, bool frameWritten)
{
    const double endTimeS = (frameCount - 1) / sim.scene().frameRateHz;
    return {frame, frameCount, timeS, sim.bodies().size(), steps, elapsedS, endTimeS, frameWritten, latticeParticles(sim)};
}

/// Writes frames firstFrame .. frameCount-1 of a simulation that stands at firstFrame's start.
/// After each frame's outputs, a checkpoint when output.checkpoint_every_s of wall-clock time
/// has passed since the last, or when the callback asks to stop.
RunReport runFrames(Simulation& sim, int firstFrame, int frameCount, int64_t stepsSoFar, const RunOptions& options,
                    const std::function<bool(const RunProgress&)>& onFrame, std::unique_ptr<HistoryWriter> historyWriter)
{
    const auto start = std::chrono::steady_clock::now();
    auto lastCheckpoint = start;
    const Scene& scene = sim.scene();
    const std::filesystem::path dir = options.outputDirectory;
    const std::filesystem::path checkpointPath = dir / kCheckpointFileName;
    const std::string checkpointScene = sceneToJson(scene).dump();
    RunReport report;
    const auto sinks = frameSinks(sim, options, frameCount, std::move(historyWriter), report.gltf);
    report.totalSteps = stepsSoFar;
    const auto saveCheckpoint = [&](int framesDone) {
        writeCheckpoint(checkpointPath.string(), {framesDone, frameCount, report.totalSteps, checkpointScene, sim.state()});
    };
    auto lastReport = start;
    const auto elapsedS = [&](std::chrono::steady_clock::time_point now) { return std::chrono::duration<double>(now - start).count(); };
    for (int f = firstFrame; f < frameCount; ++f) {
        const double t = f / scene.frameRateHz;
        const auto reportWithinFrame = [&] {
            const auto now = std::chrono::steady_clock::now();
            if (!onFrame || std::chrono::duration<double>(now - lastReport).count() < options.progressEveryS) return;
            lastReport = now;
            const int64_t steps = report.totalSteps + sim.state().stepStats.steps;
            onFrame(progressOf(sim, f, frameCount, sim.timeS(), steps, elapsedS(now), false));
        };
        if (!sim.advanceTo(t, options.interrupter, reportWithinFrame)) {
            // Asked to stop within the frame (a frame of the deformable phase can take minutes):
            // the state between two steps is saved, frame f still to write.
            if (scene.output.checkpointEveryS > 0) saveCheckpoint(f);
            break;
        }
        const StepStats stats = sim.takeStepStats();
        report.totalSteps += stats.steps;
        for (const auto& sink : sinks) sink->write(sim, {f, t, stats});
        report.framesWritten = f + 1;
        const auto now = std::chrono::steady_clock::now();
        lastReport = now;
        const bool stop = onFrame && !onFrame(progressOf(sim, f, frameCount, t, report.totalSteps, elapsedS(now), true)) && f + 1 < frameCount;
        // The checkpoint goes after the frame's outputs: whatever it says is written, is.
        const double every = scene.output.checkpointEveryS;
        if (every > 0 && f + 1 < frameCount && (stop || std::chrono::duration<double>(now - lastCheckpoint).count() >= every)) {
            saveCheckpoint(f + 1);
            lastCheckpoint = std::chrono::steady_clock::now();
        }
        if (stop) break;
    }
    report.complete = report.framesWritten == frameCount;
    for (const auto& sink : sinks) sink->finish({report.complete, firstFrame > 0});
    if (report.complete) {
        std::error_code ec;
        std::filesystem::remove(checkpointPath, ec);  // the run is whole; nothing to resume
    }
    report.finalBodies = sim.bodies().size();
    report.fractureEvents = static_cast<int64_t>(sim.fractureEvents().size());
    report.wallTimeS = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

/// Holds OUTDIR/run.lock (an exclusive flock) for a run's life, so a second run into the same
/// directory is refused instead of interleaving its files with the first's; the kernel releases
/// it when the process ends, however it ends.
class OutputDirectoryLock {
public:
    explicit OutputDirectoryLock(const std::filesystem::path& dir)
    {
        const std::string path = (dir / kRunLockFileName).string();
        mFd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (mFd < 0) throw IoError(path + ": cannot open the run's lock file: " + std::strerror(errno));
        if (::flock(mFd, LOCK_EX | LOCK_NB) != 0) {
            ::close(mFd);
            throw IoError(dir.string() + ": another spall run is writing to this directory (it holds " + path + ")");
        }
    }
    ~OutputDirectoryLock() { ::close(mFd); }
    OutputDirectoryLock(const OutputDirectoryLock&) = delete;
    OutputDirectoryLock& operator=(const OutputDirectoryLock&) = delete;

private:
    int mFd = -1;
};

/// runScene once the directory exists and is locked.
RunReport runSceneInLockedDirectory(const Scene& scene, const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame)
{
    namespace fs = std::filesystem;
    const fs::path dir = options.outputDirectory;
    std::error_code ec;
    // A checkpoint of an earlier run in the same directory must not be resumed into this one.
    fs::remove(dir / kCheckpointFileName, ec);
    const nlohmann::json resolvedScene = sceneToJson(scene);
    writeFileAtomically((dir / "scene.json").string(), [&](std::ostream& out) { out << resolvedScene.dump(2) << "\n"; });

    Simulation sim(scene, options.interrupter);
    if (options.onNote)
        for (const std::string& note : sim.notes()) options.onNote(note);
    const int frameCount = options.maxFrames >= 0 ? std::min(options.maxFrames, scene.frameCount()) : scene.frameCount();

    std::unique_ptr<HistoryWriter> history;
    if (scene.output.history) {
        HistoryHeader header;
        header.voxelSizeM = scene.voxelSizeM;
        header.seed = scene.seed;
        header.sceneJson = resolvedScene.dump();
        for (const Charge& c : scene.charges) header.charges.push_back({c.positionM, c.tntKg, c.detonationTimeS, enumName(c.burst)});
        history = std::make_unique<HistoryWriter>((dir / "history.h5").string(), header);
    }
    return runFrames(sim, 0, frameCount, 0, options, onFrame, std::move(history));
}

}  // namespace

RunReport runScene(const Scene& scene, const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame)
{
    namespace fs = std::filesystem;
    const fs::path dir = options.outputDirectory;
    if (!options.gltfPath.empty()) requireLevelSetFrames(scene.output);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw IoError(dir.string() + ": cannot create the output directory: " + ec.message());
    const OutputDirectoryLock lock(dir);
    return runSceneInLockedDirectory(scene, options, onFrame);
}

RunReport resumeRun(const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame)
{
    namespace fs = std::filesystem;
    const fs::path dir = options.outputDirectory;
    const std::string path = (dir / kCheckpointFileName).string();
    if (!fs::is_directory(dir)) throw IoError(dir.string() + ": nothing to resume: there is no " + path + " (no such directory)");
    const OutputDirectoryLock lock(dir);
    if (!fs::exists(path) && fs::exists(dir / "history.h5") && readHistory((dir / "history.h5").string()).runComplete)
        throw InputError(dir.string() + ": the run is complete (history.h5 says run_complete = 1); there is nothing to resume");
    if (!fs::exists(path)) {
        // Killed before its first checkpoint: run the resolved scene again from the start.
        const fs::path scenePath = dir / "scene.json";
        if (!fs::exists(scenePath))
            throw IoError(dir.string() + ": nothing to resume: there is no " + path + " and no " + scenePath.string() +
                          " (the run had not started writing)");
        const Scene scene = loadScene(scenePath.string());
        if (!options.gltfPath.empty()) requireLevelSetFrames(scene.output);
        RunReport report = runSceneInLockedDirectory(scene, options, onFrame);
        report.restartedFromScene = true;
        return report;
    }
    Checkpoint checkpoint = readCheckpoint(path);
    const Scene scene = parseScene(checkpoint.sceneJson, path + " (scene)", dir.string());
    if (!options.gltfPath.empty()) requireLevelSetFrames(scene.output);
    std::unique_ptr<HistoryWriter> history;
    if (scene.output.history)
        history = std::make_unique<HistoryWriter>(
            (dir / "history.h5").string(),
            HistoryResumePoint{checkpoint.framesDone, static_cast<int64_t>(checkpoint.state.events.size()),
                               static_cast<int64_t>(checkpoint.state.dust.size())});
    Simulation sim(scene, std::move(checkpoint.state));
    return runFrames(sim, checkpoint.framesDone, checkpoint.frameCount, checkpoint.totalSteps, options, onFrame, std::move(history));
}

}  // namespace spall
