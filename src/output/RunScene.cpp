#include <spall/output/RunScene.h>

#include <filesystem>

namespace spall {

std::optional<Scene> sceneOfRun(const std::string& outDir)
{
    const std::string path = (std::filesystem::path(outDir) / "scene.json").string();
    if (!std::filesystem::exists(path)) return std::nullopt;
    return loadScene(path);
}

}  // namespace spall
