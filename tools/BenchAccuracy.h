// `spall bench accuracy`: error against a reference next to run time, for the blast table, the
// integrators on closed-form problems, pressure at link midpoints against voxel centres, and the
// time-step tolerances and voxel size on the default scene. Writes accuracy.csv and log-log PNGs.
#pragma once

#include <string>

namespace spall {

/// Runs every study, prints tables and writes OUTDIR/accuracy.csv and OUTDIR/accuracy-*.png.
/// `sceneDurationS` is how much of the default scene the whole-scene study simulates per variant.
/// Returns the exit code.
int benchAccuracy(const std::string& outputDirectory, double sceneDurationS);

}  // namespace spall
