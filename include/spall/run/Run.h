// A whole run: scene -> simulation -> frames (.vdb) and history (.h5) in an output directory.
#pragma once

#include <spall/core/Error.h>
#include <spall/output/GltfExport.h>
#include <spall/scene/Scene.h>

#include <functional>
#include <optional>
#include <string>

namespace spall {

/// The file a run holds locked in its output directory while it writes there.
inline constexpr const char* kRunLockFileName = "run.lock";

/// Whether a file in an output directory is one spall writes there: a run's scene.json,
/// history.h5, checkpoint, fragments.NNNN.vdb and preview.png, what spall debris, export,
/// view and render write from them, and what a write cut short left (NAME.partial.PID).
bool isRunOutputName(const std::string& fileName);

struct RunOptions {
    std::string outputDirectory = "out";
    /// A fresh run into a directory that holds an earlier run's output (its files by the names
    /// spall writes: isRunOutputName) replaces them; otherwise it is refused, so two runs never
    /// mix in one directory.
    bool replaceEarlierRun = false;
    int maxFrames = -1;  ///< stop after this many frames (-1: the scene's duration)
    /// When set, a contact sheet of `previewFrames` frames spread over the run is rendered here
    /// from the bodies in memory (no frame files are read back).
    std::string previewPath;
    int previewFrames = 6;
    /// When set, the debris as one .glb here once the run completes (output/GltfExport.h: needs
    /// level-set frames, checked before the run starts); `onGltfFrame(done, total)` follows the
    /// export's progress and may be empty.
    std::string gltfPath;
    std::function<void(int, int)> onGltfFrame;
    /// Asked while voxelising large meshes; may be null.
    Interrupter* interrupter = nullptr;
    /// Told what setting the scene up found that a user should know (mesh repairs, memory at
    /// risk), before the first step; may be empty.
    std::function<void(const std::string&)> onNote;
    /// How often a frame that takes long reports its progress to the callback (unit: s of wall
    /// clock; 0: after every step).
    double progressEveryS = 1.0;
};

/// What the progress callback sees after each frame, and about once a second within a long
/// frame (a frame of the deformable phase can take many minutes).
struct RunProgress {
    int frame = 0;  ///< the frame written, or the one being computed
    int frameCount = 0;
    double timeS = 0;  ///< simulated (unit: s)
    size_t bodies = 0;
    int64_t totalSteps = 0;  ///< so far
    double elapsedS = 0;     ///< wall clock since this run (or resume) began (unit: s)
    double endTimeS = 0;     ///< the last frame's time (unit: s)
    bool frameWritten = true;  ///< false: a report from within frame `frame`
    /// Particles of the lattices in the deformable phase: while there are any, a simulated
    /// second costs far more than it will in the flight after it.
    size_t latticeParticles = 0;
    /// The particle-steps the lattices have taken since this run (or resume) began, and the
    /// most they can still take (DeformablePhase::particleStepsLeftAtMost): with the pace so far,
    /// a bound on the phase's time to come.
    int64_t latticeParticleSteps = 0;
    int64_t latticeParticleStepsLeftAtMost = 0;
};

struct RunReport {
    int framesWritten = 0;
    bool complete = false;  ///< false when interrupted
    /// Stopped within a step that took too long to wait for (Interrupter::mustAbandonStep): the
    /// step's work is lost, no checkpoint was written for it, and a resume goes on from the last one.
    bool stepAbandoned = false;
    int64_t totalSteps = 0;
    size_t finalBodies = 0;
    int64_t fractureEvents = 0;
    double wallTimeS = 0;
    /// --resume found no checkpoint and ran the scene again from OUTDIR/scene.json (the run is
    /// deterministic: the frames already written come out the same).
    bool restartedFromScene = false;
    std::optional<GltfExportReport> gltf;  ///< what the .glb holds, when one was asked for and written
};

/// Runs a scene and writes OUTDIR/scene.json, fragments.NNNN.vdb, history.h5 and, after each
/// frame but the last, checkpoint.spall, through the frame sinks (run/FrameSink.h) the scene and
/// the options ask for. The callback returns false to stop after the current
/// frame (frames written so far stay readable; the checkpoint lets the run continue).
RunReport runScene(const Scene& scene, const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame);

/// Continues the run in options.outputDirectory from its checkpoint: frames and history rows
/// after it are rewritten, and the run ends exactly as if it had never stopped. The scene,
/// seed and frame count are the checkpoint's; maxFrames is ignored.
RunReport resumeRun(const RunOptions& options, const std::function<bool(const RunProgress&)>& onFrame);

}  // namespace spall
