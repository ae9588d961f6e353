#include <spall/sim/MemoryBudget.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>

namespace spall {

namespace {

constexpr double kProgramBytes = 60e6;           // the default scene's peak with no body broken
constexpr double kIntactBytesPerVoxel = 24.0;    // 1.5 M voxels whole: +31 MB over 24 000 voxels
constexpr double kFragmentBytesPerVoxel = 28e3;  // 24 000 one-voxel fragments: +620 MB

/// The value of `key` in /proc/meminfo (unit: bytes), or -1.
double meminfoBytes(const std::string& key)
{
    std::ifstream meminfo("/proc/meminfo");
    std::string line;
    while (std::getline(meminfo, line)) {
        if (line.compare(0, key.size() + 1, key + ":") != 0) continue;
        std::istringstream fields(line.substr(key.size() + 1));
        double kib = -1;
        fields >> kib;
        return kib >= 0 ? kib * 1024.0 : -1.0;
    }
    return -1.0;
}

/// What a cgroup v2 limit leaves (memory.max less memory.current), or -1 without a limit.
double cgroupRoomBytes()
{
    std::ifstream maxFile("/sys/fs/cgroup/memory.max"), currentFile("/sys/fs/cgroup/memory.current");
    std::string max;
    double current = 0;
    if (!(maxFile >> max) || max == "max" || !(currentFile >> current)) return -1.0;
    try {
        return std::max(0.0, std::stod(max) - current);
    } catch (const std::exception&) {
        return -1.0;
    }
}

}  // namespace

MemoryEstimate estimateMemory(double voxels)
{
    MemoryEstimate estimate;
    estimate.intactBytes = kProgramBytes + kIntactBytesPerVoxel * voxels;
    estimate.allBrokenBytes = kProgramBytes + kFragmentBytesPerVoxel * voxels;
    return estimate;
}

double availableMemoryBytes()
{
    const double kernel = meminfoBytes("MemAvailable");
    const double cgroup = cgroupRoomBytes();
    if (kernel < 0) return cgroup;
    return cgroup < 0 ? kernel : std::min(kernel, cgroup);
}

}  // namespace spall
