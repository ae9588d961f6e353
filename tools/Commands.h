// The subcommands of `spall`, one file each; tools/spall.cpp parses the command line and calls them.
// Each returns the process's exit code and throws spall's errors, which main turns into codes.
#pragma once

#include <cstdint>
#include <string>

int runVoxelise(const std::string& input, const std::string& primitiveSpec, const std::string& output, double voxelSizeM,
                int64_t maxVoxels, bool quiet);
int runBlast(double tntKg, double distanceM, const std::string& burstName, const std::string& datasetName, bool json,
             const std::string& curvePath);
int runInspect(const std::string& path, bool json, int frameArg, int64_t bodyArg);
int runRender(const std::string& outDir, int frame, bool all, bool sheet, std::string pictureDir, const std::string& size);
int runRun(const std::string& scenePath, const std::string& outDir, bool resume, int threads, int64_t seed, int frames, bool quiet,
           bool preview);
