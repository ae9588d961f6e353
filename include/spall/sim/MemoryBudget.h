// What a run will hold in memory, estimated from its voxel count before anything is allocated, and
// what the machine can give it.
#pragma once

#include <cstdint>

namespace spall {

struct MemoryEstimate {
    double intactBytes = 0;     ///< every object whole (unit: bytes)
    double allBrokenBytes = 0;  ///< every voxel a fragment of its own, where today's fracture rules can go (unit: bytes)
};

/// From figures measured on the default wall (docs/performance.md, "Memory"): about 24 bytes per
/// voxel of a whole body and about 28 KB per one-voxel fragment (its grids, faces and contacts),
/// on top of the program itself.
MemoryEstimate estimateMemory(double voxels);

/// Memory this process can still take (unit: bytes): the kernel's MemAvailable, or less under a
/// cgroup memory limit; negative when neither can be read.
double availableMemoryBytes();

}  // namespace spall
