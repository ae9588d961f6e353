// `spall render`: preview pictures of a run's frames.
#include "Commands.h"

#include <memory>

#include <spall/core/Error.h>
#include <spall/output/Png.h>
#include <spall/output/FrameWriter.h>
#include <spall/output/RunScene.h>
#include <spall/voxel/VdbIo.h>
#include <spall/render/Render.h>

#include <cstdio>
#include <filesystem>

namespace {

/// The camera the options ask for: the one that frames the run's first and last frames, moved to
/// `eye` and turned to `target` where those are given.
struct CameraOptions {
    std::vector<double> eyeM, targetM;
    double verticalFovDeg = 0.0;  ///< 0: the default
};
spall::Camera chooseCamera(const std::vector<std::string>& paths, const spall::RenderSettings& settings, const CameraOptions& options)
{
    const spall::FrameGrids first = spall::readFrame(paths.front()), last = spall::readFrame(paths.back());
    spall::Camera camera = spall::frameCamera({spall::fragmentsOf(first), spall::fragmentsOf(last)}, settings);
    if (options.eyeM.size() == 3) camera.eyeM = Eigen::Vector3d(options.eyeM[0], options.eyeM[1], options.eyeM[2]);
    if (options.targetM.size() == 3) camera.targetM = Eigen::Vector3d(options.targetM[0], options.targetM[1], options.targetM[2]);
    if (options.verticalFovDeg > 0.0) camera.verticalFovDeg = options.verticalFovDeg;
    if ((camera.targetM - camera.eyeM).norm() < 1e-6) throw spall::InputError("--eye and --target are the same point: the camera looks nowhere");
    return camera;
}

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


int runRender(const std::string& outDir, int frame, bool all, bool sheet, std::string pictureDir, const std::string& size,
              const CameraOptions& cameraOptions)
{
    spall::RenderSettings settings = parseSize(size);
    if (const std::optional<spall::Scene> scene = spall::sceneOfRun(outDir))
        for (const spall::Charge& charge : scene->charges) settings.chargesM.push_back(charge.positionM);
    const std::vector<std::string> paths = spall::listFramePaths(outDir);
    const spall::Camera camera = chooseCamera(paths, settings, cameraOptions);
    if (pictureDir.empty()) pictureDir = outDir;
    std::filesystem::create_directories(pictureDir);
    if (sheet) {
        const std::string path = (std::filesystem::path(pictureDir) / "sheet.png").string();
        const int n = spall::writeContactSheet(outDir, path, 9, settings, camera);
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
        CameraOptions camera;
    };
    auto o = std::make_shared<Options>();
    auto* sub = app.add_subcommand("render", "Render preview pictures (PNG) of a run's frames");
    sub->add_option("outdir", o->directory, "A spall run's output directory")->required();
    sub->add_option("--frame", o->frame, "Frame number (default: the last)");
    sub->add_flag("--all", o->all, "Every frame");
    sub->add_flag("--sheet", o->sheet, "A contact sheet of nine frames across the run");
    sub->add_option("-o,--output", o->output, "Where the pictures go (default: the output directory)");
    sub->add_option("--size", o->size, "WIDTHxHEIGHT in pixels");
    sub->add_option("--eye", o->camera.eyeM, "X,Y,Z: where the camera stands, in metres (default: where it frames the first and last frames)")
        ->delimiter(',')->expected(3);
    sub->add_option("--target", o->camera.targetM, "X,Y,Z: the point it looks at, in metres (default: the debris' centre)")->delimiter(',')->expected(3);
    sub->add_option("--fov", o->camera.verticalFovDeg, "Vertical field of view in degrees (default 40)")->check(CLI::Range(1.0, 170.0));
    sub->callback([o, &action] {
        action = [o] { return runRender(o->directory, o->frame, o->all, o->sheet, o->output, o->size, o->camera); };
    });
}
