#include <spall/run/FrameSink.h>

#include <spall/core/Error.h>
#include <spall/dynamics/Integrate.h>
#include <spall/output/FrameWriter.h>
#include <spall/output/History.h>
#include <spall/render/Render.h>

#include <algorithm>
#include <cmath>

namespace spall {

namespace {

class VdbSink : public FrameSink {
public:
    VdbSink(const std::string& directory, const OutputSettings& settings, std::vector<Material> materials)
        : mWriter(directory, settings, std::move(materials))
    {
    }
    void write(const Simulation& sim, const FrameStamp& frame) override
    {
        mWriter.write({frame.frame, frame.timeS, sim.scene().frameRateHz}, frame.bodies);
    }
    void finish(const RunEnd&) override {}

private:
    FrameWriter mWriter;
};

/// The frame's totals over its bodies, and a row per body it shows: the totals count a lattice's
/// particles (Simulation::bodyMomenta), the rows its pieces' rigid fits.
FrameRow frameTotals(const Simulation& sim, const FrameStamp& frame, std::vector<BodyRow>& rows)
{
    FrameRow row;
    row.timeS = frame.timeS;
    row.brokenLinks = frame.stats.brokenLinks;
    row.steps = frame.stats.steps;
    row.minDtS = frame.stats.steps > 0 ? frame.stats.minDtS : 0.0;
    row.latticeParticleSteps = frame.stats.latticeParticleSteps;
    row.bodyCount = static_cast<int64_t>(frame.bodies.size());
    for (const BodyMomenta& m : sim.bodyMomenta()) {
        row.kineticEnergyJ += m.kineticEnergyJ;
        row.linearMomentum += m.linearMomentumKgMS;
        row.angularMomentum += m.angularMomentumKgM2S;
    }
    rows.reserve(frame.bodies.size());
    for (const Body& b : frame.bodies) {
        row.voxelCount += b.mass.voxelCount;
        const Eigen::Quaterniond& q = b.motion.orientation;
        rows.push_back({b.id, b.parentId, b.motion.positionM, Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()), b.motion.linearVelocityMS,
                        b.motion.angularVelocityRadS, b.mass.massKg, b.mass.voxelCount, b.motion.asleep, b.anchored});
    }
    for (const DustRecord& d : sim.dust()) row.dustMassKg += d.massKg;
    for (const HandOffRecord& h : sim.state().handOffs) row.discardedVibrationJ += h.discardedEnergyJ;
    return row;
}

class HistorySink : public FrameSink {
public:
    HistorySink(std::unique_ptr<HistoryWriter> writer, const RecordsWritten& written)
        : mWriter(std::move(writer)), mEventsWritten(size_t(written.fractureEvents)), mDustWritten(size_t(written.dust))
    {
    }

    void write(const Simulation& sim, const FrameStamp& frame) override
    {
        std::vector<BodyRow> rows;
        const FrameRow row = frameTotals(sim, frame, rows);
        const auto& events = sim.fractureEvents();
        const auto& dust = sim.dust();
        mWriter->appendFrame(row, rows, {events.begin() + mEventsWritten, events.end()}, {dust.begin() + mDustWritten, dust.end()});
        mEventsWritten = events.size();
        mDustWritten = dust.size();
    }

    void finish(const RunEnd& end) override
    {
        if (end.complete) mWriter->finish();
    }

private:
    std::unique_ptr<HistoryWriter> mWriter;
    size_t mEventsWritten, mDustWritten;
};

/// Copies of the chosen frames' bodies share their grids, whose active voxels never change once
/// a body exists.
class PreviewSink : public FrameSink {
public:
    PreviewSink(const std::string& path, int sheetFrames, int frameCount, const Scene& scene, const std::string& directory)
        : mPath(path), mSheetFrames(sheetFrames), mDirectory(directory), mFramesOnDisk(scene.output.vdb),
          mSettings{640, 360, scene.world.ground.offsetM, {}}
    {
        for (const Charge& charge : scene.charges) mSettings.chargesM.push_back(charge.positionM);
        const int n = std::min(sheetFrames, frameCount);
        for (int i = 0; i < n; ++i) mChosen.push_back(n == 1 ? frameCount - 1 : int(std::lround(double(i) * (frameCount - 1) / (n - 1))));
    }

    void write(const Simulation&, const FrameStamp& frame) override
    {
        if (std::find(mChosen.begin(), mChosen.end(), frame.frame) == mChosen.end()) return;
        mBodies.push_back(frame.bodies);
        mTimes.push_back(frame.timeS);
    }

    /// After a resumed run the frames before the resume point are no longer in memory: they are
    /// read back from the frame files (when there are any).
    void finish(const RunEnd& end) override
    {
        if (end.complete && end.resumed) {
            if (mFramesOnDisk) writeContactSheet(mDirectory, mPath, mSheetFrames, mSettings);
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
    int mSheetFrames;
    std::string mDirectory;
    bool mFramesOnDisk;
    RenderSettings mSettings;
    std::vector<int> mChosen;
    std::vector<std::vector<Body>> mBodies;
    std::vector<double> mTimes;
};

class GltfSink : public FrameSink {
public:
    GltfSink(const std::string& directory, const std::string& glbPath, std::function<void(int, int)> onFrame,
             std::optional<GltfExportReport>& report)
        : mDirectory(directory), mGlbPath(glbPath), mOnFrame(std::move(onFrame)), mReport(report)
    {
    }
    void write(const Simulation&, const FrameStamp&) override {}
    void finish(const RunEnd& end) override
    {
        if (end.complete) mReport = exportGltf(mDirectory, mGlbPath, mOnFrame);
    }

private:
    std::string mDirectory, mGlbPath;
    std::function<void(int, int)> mOnFrame;
    std::optional<GltfExportReport>& mReport;
};

}  // namespace

std::unique_ptr<FrameSink> makeVdbSink(const std::string& directory, const OutputSettings& settings, std::vector<Material> materials)
{
    return std::make_unique<VdbSink>(directory, settings, std::move(materials));
}

std::unique_ptr<FrameSink> makeHistorySink(std::unique_ptr<HistoryWriter> writer, const RecordsWritten& written)
{
    return std::make_unique<HistorySink>(std::move(writer), written);
}

std::unique_ptr<FrameSink> makePreviewSink(const std::string& path, int sheetFrames, int frameCount, const Scene& scene,
                                           const std::string& directory)
{
    return std::make_unique<PreviewSink>(path, sheetFrames, frameCount, scene, directory);
}

void requireLevelSetFrames(const OutputSettings& settings)
{
    if (!settings.vdb || settings.fragmentGrids != FragmentGrids::LevelSet)
        throw InputError("output: a .glb is meshed from level-set frames; this scene writes " +
                         std::string(settings.vdb ? "fog frames (output.fragment_grids \"fog\")" : "no frames (output.vdb false)"));
}

std::unique_ptr<FrameSink> makeGltfSink(const std::string& directory, const std::string& glbPath, std::function<void(int, int)> onFrame,
                                        std::optional<GltfExportReport>& report)
{
    return std::make_unique<GltfSink>(directory, glbPath, std::move(onFrame), report);
}

}  // namespace spall
