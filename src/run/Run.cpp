#include <spall/run/Run.h>

#include <spall/core/Error.h>

#include <spall/core/AtomicFile.h>
#include <spall/output/History.h>
#include <spall/run/FrameSink.h>
#include <spall/sim/Checkpoint.h>
#include <spall/sim/Simulation.h>
#include <spall/voxel/Voxelise.h>

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
#include <set>
#include <vector>

namespace spall {

namespace {

/// The sinks the scene and the options ask for, in the order they write: frames, history,
/// preview, glTF (which meshes the frames once the run completes).
std::vector<std::unique_ptr<FrameSink>> frameSinks(const Simulation& sim, const RunOptions& options, int frameCount,
                                                   std::unique_ptr<HistoryWriter> history, const RecordsWritten& written,
                                                   std::optional<GltfExportReport>& gltf)
{
    const OutputSettings& output = sim.scene().output;
    std::vector<std::unique_ptr<FrameSink>> sinks;
    if (output.vdb) sinks.push_back(makeVdbSink(options.outputDirectory, output, sim.scene().materials));
    if (history) sinks.push_back(makeHistorySink(std::move(history), written));
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
RunProgress progressOf(const Simulation& sim, int frame, int frameCount, double timeS, int64_t steps, double elapsedS, bool frameWritten,
                       int64_t latticeParticleSteps)
{
    const double endTimeS = (frameCount - 1) / sim.scene().frameRateHz;
    return {frame,
            frameCount,
            timeS,
            sim.bodies().size(),
            steps,
            elapsedS,
            endTimeS,
            frameWritten,
            latticeParticles(sim),
            latticeParticleSteps,
            sim.state().deformable.particleStepsLeftAtMost(sim.timeS(), sim.scene().lattice.maxVibrationS)};
}

/// How stepping to a frame's time ended.
enum class FrameAdvance { Reached, Stopped, Abandoned };

/// Simulation::advanceTo, its StepAbandoned an outcome: Stopped leaves the state between two
/// steps (fit for a checkpoint), Abandoned within one (the last checkpoint stands).
FrameAdvance advanceToFrame(Simulation& sim, double timeS, Interrupter* interrupter, const std::function<void()>& afterStep)
{
    try {
        return sim.advanceTo(timeS, interrupter, afterStep) ? FrameAdvance::Reached : FrameAdvance::Stopped;
    } catch (const StepAbandoned&) {
        return FrameAdvance::Abandoned;
    }
}

/// Writes frames firstFrame .. frameCount-1 of a simulation that stands at or within firstFrame's
/// start, the frames before it holding `written` of its records. After each frame's outputs, a
/// checkpoint when output.checkpoint_every_s of wall-clock time has passed since the last, or
/// when the callback asks to stop.
RunReport runFrames(Simulation& sim, int firstFrame, int frameCount, int64_t stepsSoFar, RecordsWritten written, const RunOptions& options,
                    const std::function<bool(const RunProgress&)>& onFrame, std::unique_ptr<HistoryWriter> historyWriter)
{
    const auto start = std::chrono::steady_clock::now();
    auto lastCheckpoint = start;
    const Scene& scene = sim.scene();
    const std::filesystem::path dir = options.outputDirectory;
    const std::filesystem::path checkpointPath = dir / kCheckpointFileName;
    const std::string checkpointScene = sceneToJson(scene).dump();
    RunReport report;
    report.framesWritten = firstFrame;  // a resumed run's frames before its checkpoint are written too
    const auto sinks = frameSinks(sim, options, frameCount, std::move(historyWriter), written, report.gltf);
    report.totalSteps = stepsSoFar;
    const auto saveCheckpoint = [&](int framesDone) {
        writeCheckpoint(checkpointPath.string(), {framesDone, frameCount, report.totalSteps, checkpointScene, sim.state(), written});
    };
    auto lastReport = start;
    int64_t latticeStepsDone = 0;  // in the frames written
    const auto elapsedS = [&](std::chrono::steady_clock::time_point now) { return std::chrono::duration<double>(now - start).count(); };
    for (int f = firstFrame; f < frameCount; ++f) {
        const double t = f / scene.frameRateHz;
        const auto reportWithinFrame = [&] {
            const auto now = std::chrono::steady_clock::now();
            if (!onFrame || std::chrono::duration<double>(now - lastReport).count() < options.progressEveryS) return;
            lastReport = now;
            const int64_t steps = report.totalSteps + sim.state().stepStats.steps;
            onFrame(progressOf(sim, f, frameCount, sim.timeS(), steps, elapsedS(now), false, latticeStepsDone + sim.state().stepStats.latticeParticleSteps));
        };
        const FrameAdvance advance = advanceToFrame(sim, t, options.interrupter, reportWithinFrame);
        report.stepAbandoned = advance == FrameAdvance::Abandoned;
        if (report.stepAbandoned) break;
        if (advance == FrameAdvance::Stopped) {
            // Asked to stop within the frame (a frame of the deformable phase can take minutes):
            // the state between two steps is saved, frame f still to write.
            if (scene.output.checkpointEveryS > 0) saveCheckpoint(f);
            report.totalSteps += sim.state().stepStats.steps;  // what the summary counts: the unfinished frame's too
            break;
        }
        const StepStats stats = sim.takeStepStats();
        report.totalSteps += stats.steps;
        latticeStepsDone += stats.latticeParticleSteps;
        const std::vector<Body> shown = sim.showPieces();
        for (const auto& sink : sinks) sink->write(sim, {f, t, stats, shown});
        written = {int64_t(sim.fractureEvents().size()), int64_t(sim.dust().size())};
        report.framesWritten = f + 1;
        const auto now = std::chrono::steady_clock::now();
        lastReport = now;
        const bool stop = onFrame && !onFrame(progressOf(sim, f, frameCount, t, report.totalSteps, elapsedS(now), true, latticeStepsDone)) && f + 1 < frameCount;
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
    explicit OutputDirectoryLock(const std::filesystem::path& dir) : mPath((dir / kRunLockFileName).string())
    {
        mFd = ::open(mPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (mFd < 0) throw IoError(mPath + ": cannot open the run's lock file: " + std::strerror(errno));
        if (::flock(mFd, LOCK_EX | LOCK_NB) != 0) {
            ::close(mFd);
            throw IoError(dir.string() + ": another spall run is writing to this directory (it holds " + mPath + ")");
        }
    }
    /// The lock file goes with the run, so a directory holds only outputs once it ends (a run
    /// that dies keeps it, harmlessly: the kernel has released its lock).
    ~OutputDirectoryLock()
    {
        ::unlink(mPath.c_str());
        ::close(mFd);
    }
    OutputDirectoryLock(const OutputDirectoryLock&) = delete;
    OutputDirectoryLock& operator=(const OutputDirectoryLock&) = delete;

private:
    std::string mPath;
    int mFd = -1;
};

/// The files an earlier run (or what read it) left in a directory, in name order.
std::vector<std::filesystem::path> earlierRunOutputs(const std::filesystem::path& dir)
{
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
        if (entry.is_regular_file() && isRunOutputName(entry.path().filename().string())) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    return files;
}

/// A fresh run starts in a directory with no earlier run's output: what is there is removed when
/// `replace`, else the run is refused, naming what is there and the ways on.
void clearEarlierRun(const std::filesystem::path& dir, bool replace)
{
    const std::vector<std::filesystem::path> files = earlierRunOutputs(dir);
    if (files.empty()) return;
    if (!replace) {
        const auto frames = std::count_if(files.begin(), files.end(), [](const auto& f) { return f.filename().string().rfind("fragments.", 0) == 0; });
        std::string listed;
        for (const auto& f : files)
            if (f.filename().string().rfind("fragments.", 0) != 0 && listed.size() < 120) listed += (listed.empty() ? "" : ", ") + f.filename().string();
        throw InputError(dir.string() + ": holds the output of an earlier run (" + listed + (frames > 0 ? (listed.empty() ? "" : ", ") + std::to_string(frames) + " frames" : "") +
                         "), which a new run would mix with; give --overwrite to replace it, continue it with spall run --resume " + dir.string() +
                         ", or choose another output directory");
    }
    for (const auto& f : files) {
        std::error_code ec;
        std::filesystem::remove(f, ec);
        if (ec) throw IoError(f.string() + ": cannot remove the earlier run's file: " + ec.message());
    }
}

/// runScene once the directory exists and is locked.
RunReport runSceneInLockedDirectory(const Scene& scene, const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame)
{
    namespace fs = std::filesystem;
    const fs::path dir = options.outputDirectory;
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
    return runFrames(sim, 0, frameCount, 0, {}, options, onFrame, std::move(history));
}

}  // namespace

bool isRunOutputName(const std::string& fileName)
{
    static const std::set<std::string> kNames = {"scene.json", "history.h5", kCheckpointFileName, "preview.png", "debris.h5", "debris.csv",
                                                 "debris_throw.png", "debris_density.png", "debris_mass.png", "debris.glb", "view.html",
                                                 "sheet.png"};
    const auto numbered = [&](const char* prefix, const char* suffix) {
        const std::string p = prefix, s = suffix;
        if (fileName.size() != p.size() + 4 + s.size() || fileName.compare(0, p.size(), p) != 0 || fileName.compare(fileName.size() - s.size(), s.size(), s) != 0)
            return false;
        return std::all_of(fileName.begin() + long(p.size()), fileName.end() - long(s.size()), [](char c) { return c >= '0' && c <= '9'; });
    };
    const size_t partial = fileName.find(".partial.");
    if (partial != std::string::npos) return isRunOutputName(fileName.substr(0, partial));
    return kNames.count(fileName) > 0 || numbered("fragments.", ".vdb") || numbered("frame.", ".png");
}

RunReport runScene(const Scene& scene, const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame)
{
    namespace fs = std::filesystem;
    const fs::path dir = options.outputDirectory;
    if (!options.gltfPath.empty()) requireLevelSetFrames(scene.output);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw IoError(dir.string() + ": cannot create the output directory: " + ec.message());
    const OutputDirectoryLock lock(dir);
    clearEarlierRun(dir, options.replaceEarlierRun);
    bool wroteAFrame = false;
    const auto watched = [&](const RunProgress& progress) {
        wroteAFrame = wroteAFrame || progress.frameWritten;
        return !onFrame || onFrame(progress);
    };
    try {
        return runSceneInLockedDirectory(scene, options, watched);
    } catch (const VoxeliseInterrupted&) {
        throw;  // stopped on request: its scene.json lets --resume start it again
    } catch (...) {
        // A run that failed before its first frame leaves nothing that looks like a run.
        try {
            if (!wroteAFrame) clearEarlierRun(dir, true);
        } catch (const std::exception&) {
            // What could not be removed stays; the run's own error is the one to report.
        }
        throw;
    }
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
            HistoryResumePoint{checkpoint.framesDone, checkpoint.written.fractureEvents, checkpoint.written.dust});
    Simulation sim(scene, std::move(checkpoint.state));
    return runFrames(sim, checkpoint.framesDone, checkpoint.frameCount, checkpoint.totalSteps, checkpoint.written, options, onFrame,
                     std::move(history));
}

}  // namespace spall
