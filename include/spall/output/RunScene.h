// The scene of a finished or running run, read back from its output directory.
#pragma once

#include <spall/scene/Scene.h>

#include <optional>
#include <string>

namespace spall {

/// OUTDIR/scene.json (the scene as the run resolved it): its charges, materials and output
/// settings for what is made from the run afterwards; none when the directory has no
/// scene.json. Throws InputError naming the file and field when it cannot be read.
std::optional<Scene> sceneOfRun(const std::string& outDir);

}  // namespace spall
