// What a run writes as it reaches each frame, behind one small interface: the run loop
// (run/Run.cpp) hands every frame to each sink the scene and the options asked for, then tells
// them how the run ended. A sink nobody asked for is never made, so it costs nothing.
#pragma once

#include <spall/output/GltfExport.h>
#include <spall/sim/Checkpoint.h>
#include <spall/sim/Simulation.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace spall {

class HistoryWriter;

/// A frame reached: its index, its time, what the steps since the last frame did, and the bodies
/// it shows (Simulation::showPieces).
struct FrameStamp {
    int frame = 0;
    double timeS = 0.0;  ///< (unit: s)
    StepStats stats;
    const std::vector<Body>& bodies;
};

/// How the run ended: `complete` when its last frame was written; `resumed` when this process
/// began from a checkpoint (frames before it are on disk only).
struct RunEnd {
    bool complete = false;
    bool resumed = false;
};

class FrameSink {
public:
    virtual ~FrameSink() = default;
    virtual void write(const Simulation& sim, const FrameStamp& frame) = 0;
    /// After the last frame this process writes, whether or not the run is complete.
    virtual void finish(const RunEnd& end) = 0;
};

/// fragments.NNNN.vdb in `directory`, as output settings say (output/FrameWriter.h).
/// `materials`: the simulation's materials in order (Body::materialIndex), for the frames.
std::unique_ptr<FrameSink> makeVdbSink(const std::string& directory, const OutputSettings& settings, std::vector<Material> materials);

/// history.h5's rows: per-frame totals and per-body rows, with the fracture events and dust since
/// the last frame (the first frame it writes: since `written`); marked whole when the run completes.
std::unique_ptr<FrameSink> makeHistorySink(std::unique_ptr<HistoryWriter> writer, const RecordsWritten& written);

/// A contact sheet (PNG at `path`) of `sheetFrames` frames spread over the run's `frameCount`,
/// rendered from the bodies in memory; after a resumed run, from the frame files in `directory`.
std::unique_ptr<FrameSink> makePreviewSink(const std::string& path, int sheetFrames, int frameCount, const Scene& scene,
                                           const std::string& directory);

/// Throws InputError unless a run with these settings writes level-set frames, which a .glb is
/// meshed from: a run that asks for one is refused before it starts.
void requireLevelSetFrames(const OutputSettings& settings);

/// When the run completes, its debris as one .glb at `glbPath`, meshed from the level-set frames
/// in `directory` (output/GltfExport.h; the caller has checked requireLevelSetFrames before the
/// run); `onFrame(done, total)` reports the export's progress and the report lands in `report`.
std::unique_ptr<FrameSink> makeGltfSink(const std::string& directory, const std::string& glbPath, std::function<void(int, int)> onFrame,
                                        std::optional<GltfExportReport>& report);

}  // namespace spall
