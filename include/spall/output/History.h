// history.h5: per-frame and per-body arrays (unit in every name), a CSR offset array linking
// frames to body rows, fracture events, dust and charges. Flushed every frame, so a run that is
// interrupted keeps every frame written so far readable. Layout: docs/file-formats.md.
#pragma once

#include <spall/fracture/Events.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace spall {

inline constexpr const char* kHistoryFormatName = "spall-history";
inline constexpr int kHistoryFormatVersion = 2;

struct FrameRow {
    double timeS = 0;
    double kineticEnergyJ = 0;
    Eigen::Vector3d linearMomentum = Eigen::Vector3d::Zero();   ///< kg m/s
    Eigen::Vector3d angularMomentum = Eigen::Vector3d::Zero();  ///< kg m^2/s, about the origin
    int64_t brokenLinks = 0;  ///< since the previous frame
    int64_t steps = 0;        ///< since the previous frame
    double minDtS = 0;
    int64_t bodyCount = 0;
    int64_t voxelCount = 0;
    double dustMassKg = 0;    ///< cumulative
    int64_t latticeParticleSteps = 0;  ///< the deformable phase's steps times particles, over its bodies, since the previous frame
    double discardedVibrationJ = 0;  ///< cumulative: vibration the hand-offs left behind (HandOffRecord)
};

struct BodyRow {
    int64_t id = 0, parentId = -1;
    Eigen::Vector3d positionM = Eigen::Vector3d::Zero();
    Eigen::Vector4d orientationWxyz = Eigen::Vector4d(1, 0, 0, 0);
    Eigen::Vector3d linearVelocityMS = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularVelocityRadS = Eigen::Vector3d::Zero();
    double massKg = 0;
    int64_t voxelCount = 0;
    bool asleep = false;
    bool anchored = false;
};

struct ChargeRow {
    Eigen::Vector3d positionM;
    double tntKg;
    double detonationTimeS;
    std::string burst;
};

struct HistoryHeader {
    double voxelSizeM = 0;
    uint64_t seed = 0;
    std::string sceneJson;
    std::vector<ChargeRow> charges;
};

/// Where a resumed run picks a history up: everything after these rows is cut off.
struct HistoryResumePoint {
    int64_t frames = 0;
    int64_t fractureEvents = 0;
    int64_t dustRecords = 0;
};

/// Writes history.h5 incrementally. Throws IoError.
class HistoryWriter {
public:
    /// Creates a new history.
    HistoryWriter(const std::string& path, const HistoryHeader& header);
    /// Continues an existing one from a checkpoint (rows a later, lost frame wrote are cut off).
    HistoryWriter(const std::string& path, const HistoryResumePoint& resume);
    ~HistoryWriter();
    HistoryWriter(const HistoryWriter&) = delete;
    HistoryWriter& operator=(const HistoryWriter&) = delete;

    /// Appends one frame with its bodies and the events and dust since the last frame; flushes.
    void appendFrame(const FrameRow& frame, const std::vector<BodyRow>& bodies, const std::vector<FractureEvent>& events,
                     const std::vector<DustRecord>& dust);
    /// Marks the run complete (root attribute run_complete = 1) and closes the file.
    void finish();

    struct Impl;

private:
    std::unique_ptr<Impl> mImpl;
};


/// Whole-file reader for history.h5 (for `spall inspect` and tests). Throws IoError naming the
/// file when it is missing, not HDF5, or not a spall history.
struct History {
    int formatVersion = 0;
    bool runComplete = false;
    double voxelSizeM = 0;
    uint64_t seed = 0;
    std::vector<double> timeS, kineticEnergyJ, minDtS, dustMassKg, discardedVibrationJ;
    std::vector<int64_t> bodyOffset, brokenLinks, steps, bodyCount, voxelCount, latticeParticleSteps;
    std::vector<Eigen::Vector3d> linearMomentum, angularMomentum;
    std::vector<int64_t> bodyId, bodyParentId, bodyVoxelCount;
    std::vector<double> bodyMassKg;
    std::vector<Eigen::Vector3d> bodyPositionM, bodyLinearVelocityMS;
    std::vector<int8_t> bodyAsleep, bodyAnchored;
    std::vector<double> eventTimeS;
    std::vector<int64_t> eventParentId, eventChildOffset;
    std::vector<Eigen::Vector3d> chargePositionM;
    std::vector<double> chargeTntKg;
    size_t frameCount() const { return timeS.size(); }
};

History readHistory(const std::string& path);

}  // namespace spall
