// `spall export gltf OUTDIR`: a run's debris as meshes with transforms (debris.glb).
#include "Commands.h"

#include <spall/output/GltfExport.h>

#include <cstdio>
#include <filesystem>
#include <memory>

std::string defaultGlbPath(const std::string& outDir)
{
    return (std::filesystem::path(outDir) / "debris.glb").string();
}

std::function<void(int, int)> gltfProgress(bool quiet)
{
    if (quiet) return {};
    return [](int done, int total) {
        std::fprintf(stderr, "\rspall export: meshing and sampling frame %d/%d %s", done, total, done == total ? "\n" : "");
        std::fflush(stderr);
    };
}

void printGltfReport(const std::string& glbPath, const spall::GltfExportReport& r)
{
    std::printf("%s: %d fragments over %d frames, %d distinct meshes (%lld triangles), %lld pose samples, %d charge%s, %.1f MB\n",
                glbPath.c_str(), r.nodes, r.frames, r.meshes, static_cast<long long>(r.triangles), static_cast<long long>(r.keyframes),
                r.charges, r.charges == 1 ? "" : "s", r.bytes / 1e6);
}

int exportGltfCommand(const std::string& outDir, std::string glbPath, bool quiet)
{
    if (glbPath.empty()) glbPath = defaultGlbPath(outDir);
    printGltfReport(glbPath, spall::exportGltf(outDir, glbPath, gltfProgress(quiet)));
    return 0;
}

void addExportCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string outDir, output;
        bool quiet = false;
    };
    auto o = std::make_shared<Options>();
    auto* exportCommand = app.add_subcommand("export", "Write a run's debris in another format");
    exportCommand->require_subcommand(1);
    auto* gltf = exportCommand->add_subcommand("gltf", "debris.glb: each fragment meshed once, animated by its pose (glTF 2.0, Y-up, metres)");
    gltf->add_option("outdir", o->outDir, "A run's output directory (level-set frames)")->required();
    gltf->add_option("-o,--output", o->output, "The .glb to write (default OUTDIR/debris.glb)");
    gltf->add_flag("--quiet", o->quiet, "No progress");
    gltf->callback([o, &action] { action = [o] { return exportGltfCommand(o->outDir, o->output, o->quiet); }; });
}
