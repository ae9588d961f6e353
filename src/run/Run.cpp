#include <spall/run/Run.h>

#include <spall/core/AtomicFile.h>

#include <spall/dynamics/Integrate.h>
#include <spall/output/History.h>
#include <spall/output/FrameWriter.h>
#include <spall/voxel/VdbIo.h>
#include <spall/render/Render.h>
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

/// A frame's history: per-frame totals and per-body rows, with the events and dust since the
/// last frame written.
class HistoryRecorder {
public:
    HistoryRecorder(std::unique_ptr<HistoryWriter> writer, const Simulation& sim)
        : mWriter(std::move(writer)), mEventsWritten(sim.fractureEvents().size()), mDustWritten(sim.dust().size())
    {
    }

    void record(const Simulation& sim, double t, const StepStats& stats)
    {
        if (!mWriter) return;
        FrameRow row;
        row.timeS = t;
        row.brokenLinks = stats.brokenLinks;
        row.steps = stats.steps;
        row.minDtS = stats.steps > 0 ? stats.minDtS : 0.0;
        row.bodyCount = static_cast<int64_t>(sim.bodies().size());
        std::vector<BodyRow> rows;
        rows.reserve(sim.bodies().size());
        for (const Body& b : sim.bodies()) {
            row.kineticEnergyJ += kineticEnergyJ(b);
            row.linearMomentum += linearMomentum(b);
            row.angularMomentum += angularMomentumAboutOrigin(b);
            row.voxelCount += b.mass.voxelCount;
            rows.push_back({b.id, b.parentId, b.motion.positionM, Eigen::Vector4d(b.motion.orientation.w(), b.motion.orientation.x(), b.motion.orientation.y(), b.motion.orientation.z()),
                            b.motion.linearVelocityMS, b.motion.angularVelocityRadS, b.mass.massKg, b.mass.voxelCount, b.motion.asleep, b.anchored});
        }
        const auto& events = sim.fractureEvents();
        const auto& dust = sim.dust();
        for (const DustRecord& d : dust) row.dustMassKg += d.massKg;
        row.latticeParticleSteps = stats.latticeParticleSteps;
        for (const HandOffRecord& h : sim.state().handOffs) row.discardedVibrationJ += h.discardedEnergyJ;
        mWriter->appendFrame(row, rows, {events.begin() + mEventsWritten, events.end()}, {dust.begin() + mDustWritten, dust.end()});
        mEventsWritten = events.size();
        mDustWritten = dust.size();
    }

    void finish()
    {
        if (mWriter) mWriter->finish();
    }

private:
    std::unique_ptr<HistoryWriter> mWriter;
    size_t mEventsWritten, mDustWritten;
};

/// The preview: the bodies of a few frames spread over the run, rendered as a contact sheet.
/// Copies share the grids, whose active voxels never change once a body exists.
class PreviewRecorder {
public:
    PreviewRecorder(const RunOptions& options, int frameCount, const Scene& scene)
        : mPath(options.previewPath), mFrames(options.previewFrames), mSettings{640, 360, scene.world.ground.offsetM}
    {
        if (mPath.empty() || mFrames <= 0) return;
        const int n = std::min(mFrames, frameCount);
        for (int i = 0; i < n; ++i) mChosen.push_back(n == 1 ? frameCount - 1 : int(std::lround(double(i) * (frameCount - 1) / (n - 1))));
    }

    void record(int frame, double t, const std::vector<Body>& bodies)
    {
        if (std::find(mChosen.begin(), mChosen.end(), frame) == mChosen.end()) return;
        mBodies.push_back(bodies);
        mTimes.push_back(t);
    }

    /// After a resumed run the frames before the resume point are no longer in memory: they are
    /// read back from the frame files (when there are any).
    void write(bool resumedAndComplete, bool framesOnDisk, const std::string& directory) const
    {
        if (mPath.empty() || mFrames <= 0) return;
        if (resumedAndComplete) {
            if (framesOnDisk) writeContactSheet(directory, mPath, mFrames, mSettings);
            return;
        }
        if (mBodies.empty()) return;
        const Camera camera = frameCamera({fragmentsOf(mBodies.front()), fragmentsOf(mBodies.back())}, mSettings);
        std::vector<Image> images;
        for (const auto& bodies : mBodies) images.push_back(renderFragments(fragmentsOf(bodies), camera, mSettings));
        writePng(mPath, contactSheet(images, mTimes, images.size() <= 4 ? int(images.size()) : 3));
    }

private:
    std::string mPath;
    int mFrames;
    RenderSettings mSettings;
    std::vector<int> mChosen;
    std::vector<std::vector<Body>> mBodies;
    std::vector<double> mTimes;
};

/// What a run writes for each frame: the .vdb frame (when the scene asks for them), the history's
/// rows and the preview's pick, in that order.
class FrameOutputs {
public:
    FrameOutputs(const Simulation& sim, const RunOptions& options, int frameCount, std::unique_ptr<HistoryWriter> historyWriter)
        : mDirectory(options.outputDirectory), mHistory(std::move(historyWriter), sim),
          mPreview(options, frameCount, sim.scene())
    {
        if (sim.scene().output.vdb) mFrames = std::make_unique<FrameWriter>(mDirectory, sim.scene().output);
    }

    void write(const Simulation& sim, int frame, double timeS, const StepStats& stats)
    {
        if (mFrames) mFrames->write({frame, timeS}, sim.bodies());
        mHistory.record(sim, timeS, stats);
        mPreview.record(frame, timeS, sim.bodies());
    }

    /// After the last frame written: the preview, and the history marked whole when `complete`.
    void finish(bool complete, bool resumed)
    {
        mPreview.write(complete && resumed, mFrames != nullptr, mDirectory);
        if (complete) mHistory.finish();
    }

private:
    std::string mDirectory;
    std::unique_ptr<FrameWriter> mFrames;
    HistoryRecorder mHistory;
    PreviewRecorder mPreview;
};

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
    FrameOutputs outputs(sim, options, frameCount, std::move(historyWriter));
    RunReport report;
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
        outputs.write(sim, f, t, stats);
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
    outputs.finish(report.complete, firstFrame > 0);
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
        RunReport report = runSceneInLockedDirectory(loadScene(scenePath.string()), options, onFrame);
        report.restartedFromScene = true;
        return report;
    }
    Checkpoint checkpoint = readCheckpoint(path);
    const Scene scene = parseScene(checkpoint.sceneJson, path + " (scene)", dir.string());
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
