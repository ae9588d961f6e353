// `spall render`: preview pictures of a run's frames.
#include "Commands.h"

#include <memory>

#include <spall/core/Error.h>
#include <spall/output/Png.h>
#include <spall/output/FrameWriter.h>
#include <spall/voxel/VdbIo.h>
#include <spall/render/Render.h>

#include <cstdio>
#include <filesystem>

namespace {

spall::RenderSettings parseSize(const std::string& size)
{
    spall::RenderSettings s;
    int w = 0, h = 0;
    char x = 0;
    std::stringstream ss(size);
    if (!(ss >> w >> x >> h) || x != 'x' || w < 16 || h < 16 || w > 16384 || h > 16384)
        throw spall::InputError("--size '" + size + "' is not WIDTHxHEIGHT (16..16384 pixels each)");
    s.width = w;
    s.height = h;
    return s;
}


int runRender(const std::string& outDir, int frame, bool all, bool sheet, std::string pictureDir, const std::string& size)
{
    const spall::RenderSettings settings = parseSize(size);
    const std::vector<std::string> paths = spall::listFramePaths(outDir);
    if (pictureDir.empty()) pictureDir = outDir;
    std::filesystem::create_directories(pictureDir);
    if (sheet) {
        const std::string path = (std::filesystem::path(pictureDir) / "sheet.png").string();
        const int n = spall::writeContactSheet(outDir, path, 9, settings);
        std::printf("contact sheet of %d frames: %s\n", n, path.c_str());
        return 0;
    }
    std::vector<std::string> selected;
    if (all) {
        selected = paths;
    } else if (frame >= 0) {
        const std::string path = spall::FrameWriter::framePath(outDir, frame);
        if (std::find(paths.begin(), paths.end(), path) == paths.end())
            throw spall::InputError(path + ": frame " + std::to_string(frame) + " does not exist (" + std::to_string(paths.size()) + " frames)");
        selected = {path};
    } else {
        selected = {paths.back()};
    }
    const spall::FrameGrids first = spall::readFrame(paths.front()), last = spall::readFrame(paths.back());
    const spall::Camera camera = spall::frameCamera({spall::fragmentsOf(first), spall::fragmentsOf(last)}, settings);
    for (const std::string& path : selected) {
        const spall::FrameGrids f = spall::readFrame(path);
        char name[32];
        std::snprintf(name, sizeof name, "frame.%04d.png", f.frame);
        const std::string out = (std::filesystem::path(pictureDir) / name).string();
        spall::writePng(out, spall::renderFragments(spall::fragmentsOf(f), camera, settings));
        std::printf("%s\n", out.c_str());
    }
    return 0;
}

}  // namespace

void addRenderCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string directory, output, size = "960x540";
        int frame = -1;
        bool all = false, sheet = false;
    };
    auto o = std::make_shared<Options>();
    auto* sub = app.add_subcommand("render", "Render preview pictures (PNG) of a run's frames");
    sub->add_option("outdir", o->directory, "A spall run's output directory")->required();
    sub->add_option("--frame", o->frame, "Frame number (default: the last)");
    sub->add_flag("--all", o->all, "Every frame");
    sub->add_flag("--sheet", o->sheet, "A contact sheet of nine frames across the run");
    sub->add_option("-o,--output", o->output, "Where the pictures go (default: the output directory)");
    sub->add_option("--size", o->size, "WIDTHxHEIGHT in pixels");
    sub->callback([o, &action] { action = [o] { return runRender(o->directory, o->frame, o->all, o->sheet, o->output, o->size); }; });
}
