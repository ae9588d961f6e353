// `spall view OUTDIR`: the run's debris as a web page (view.html) that opens from disk.
#include "Commands.h"

#include <spall/output/FrameWriter.h>
#include <spall/output/ViewerPage.h>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace fs = std::filesystem;

namespace {

/// debris.glb is reused when it is newer than every frame; otherwise it is exported again.
bool glbIsCurrent(const std::string& outDir, const fs::path& glb)
{
    if (!fs::exists(glb)) return false;
    const auto glbTime = fs::last_write_time(glb);
    for (const std::string& frame : spall::listFramePaths(outDir))
        if (fs::last_write_time(frame) > glbTime) return false;
    return true;
}

int viewCommand(const std::string& outDir, std::string htmlPath, bool quiet)
{
    const fs::path glb = defaultGlbPath(outDir);
    if (!glbIsCurrent(outDir, glb)) exportGltfCommand(outDir, glb.string(), quiet);
    if (htmlPath.empty()) htmlPath = (fs::path(outDir) / "view.html").string();
    const std::string title = fs::absolute(outDir).lexically_normal().filename().string();
    const size_t bytes = spall::writeViewerPage(glb.string(), htmlPath, title);
    std::printf("%s: %.1f MB; open it in a browser (no server needed)\n", htmlPath.c_str(), bytes / 1e6);
    return 0;
}

}  // namespace

void addViewCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string outDir, output;
        bool quiet = false;
    };
    auto o = std::make_shared<Options>();
    auto* view = app.add_subcommand("view", "view.html: the run's debris played back in a web browser (three.js, self-contained)");
    view->add_option("outdir", o->outDir, "A run's output directory (level-set frames)")->required();
    view->add_option("-o,--output", o->output, "The page to write (default OUTDIR/view.html)");
    view->add_flag("--quiet", o->quiet, "No progress");
    view->callback([o, &action] { action = [o] { return viewCommand(o->outDir, o->output, o->quiet); }; });
}
