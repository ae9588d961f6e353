// The charges of a finished or running run, read back from its output directory.
#pragma once

#include <spall/blast/Settings.h>

#include <string>
#include <vector>

namespace spall {

/// The charges in OUTDIR/scene.json (the scene as the run resolved it): position and TNT mass;
/// none when the directory has no scene.json. Throws IoError naming the file and field when a
/// charge cannot be read.
std::vector<Charge> chargesOfRun(const std::string& outDir);

}  // namespace spall
