// checkpoint.spall: the whole state of a run after a frame, so `spall run --resume` continues an
// interrupted run and ends exactly as an uninterrupted one would. Binary, versioned, written under a
// temporary name and renamed, so the file that exists is always whole. Layout: docs/file-formats.md.
#pragma once

#include <spall/sim/Simulation.h>

#include <cstdint>
#include <string>

namespace spall {

inline constexpr const char* kCheckpointFileName = "checkpoint.spall";
inline constexpr uint32_t kCheckpointFormatVersion = 22;

/// What the frames written so far hold of the state's records (history.h5's rows of fracture
/// events and dust). A state saved within a frame holds more: the records of the frame under way.
struct RecordsWritten {
    int64_t fractureEvents = 0;
    int64_t dust = 0;
};

struct Checkpoint {
    int framesDone = 0;       ///< frames 0 .. framesDone-1 are written (the state may lie within frame framesDone)
    int frameCount = 0;       ///< frames the run writes in all
    int64_t totalSteps = 0;   ///< steps taken so far
    std::string sceneJson;    ///< the simulation's scene with every default filled in
    SimulationState state;
    RecordsWritten written;  ///< of the state's records, those frames 0 .. framesDone-1 hold
};

/// Writes atomically. Throws IoError naming the file (e.g. when the disk is full).
void writeCheckpoint(const std::string& path, const Checkpoint& checkpoint);

/// Throws IoError naming the file when it is missing, truncated, corrupt or of another version.
Checkpoint readCheckpoint(const std::string& path);

}  // namespace spall
