// spall: command-line front end. Only tools/ turns library errors into exit codes; each
// subcommand's work is in its own file (Commands.h).
#include "BenchAccuracy.h"
#include "BenchCollisions.h"
#include "Commands.h"

#include <spall/core/Error.h>

#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

int main(int argc, char** argv)
{
    CLI::App app{"spall: volumetric debris from a physically based blast"};
    app.require_subcommand(1);

    // voxelise
    auto* vox = app.add_subcommand("voxelise", "Voxelise a mesh or a primitive into a solid .vdb body");
    vox->alias("voxelize");
    std::string voxInput, voxPrimitive, voxOutput;
    double voxSize = 0.05;
    int64_t voxMax = 200'000'000;
    bool voxQuiet = false;
    vox->add_option("input", voxInput, "Mesh file (OBJ, STL, PLY, OFF, glTF, ...)");
    vox->add_option("--primitive", voxPrimitive, "Instead of a mesh: box:X,Y,Z | sphere:R | cylinder:R,H (m)");
    vox->add_option("-o,--output", voxOutput, "Output .vdb")->required();
    vox->add_option("--voxel-size", voxSize, "Voxel edge (m)")->required();
    vox->add_option("--max-voxels", voxMax, "Refuse results with more voxels than this");
    vox->add_flag("--quiet", voxQuiet, "No progress on stderr");

    // blast
    auto* blast = app.add_subcommand("blast", "Print blast-wave parameters of a TNT charge at a distance");
    double tnt = 0, dist = 0;
    std::string burst = "free-air", dataset = "kingery-bulmash", curve;
    bool blastJson = false;
    blast->add_option("--tnt-kg", tnt, "Charge mass (kg TNT)")->required();
    blast->add_option("--distance-m", dist, "Distance from the charge (m)")->required();
    blast->add_option("--burst", burst, "free-air | surface");
    blast->add_option("--dataset", dataset, "kingery-bulmash | kinney-graham");
    blast->add_flag("--json", blastJson, "JSON with SI units in every key");
    blast->add_option("--curve", curve, "Write the pressure history: .csv, or .png for a plot");

    // run
    auto* run = app.add_subcommand("run", "Simulate a scene (default: the built-in wall demo) and write frames and history");
    std::string runScenePath, runOut = "out";
    int runThreads = 0, runFrames = -1;
    int64_t runSeed = -1;
    bool runQuiet = false, runNoPreview = false;
    run->add_option("scene", runScenePath, "Scene JSON (docs/scene-format.md); omit for the built-in default");
    run->add_option("-o,--output", runOut, "Output directory");
    run->add_option("--threads", runThreads, "Worker threads (0: all cores); output does not depend on it")->check(CLI::NonNegativeNumber);
    run->add_option("--seed", runSeed, "Override the scene's seed")->check(CLI::NonNegativeNumber);
    run->add_option("--frames", runFrames, "Stop after this many frames")->check(CLI::NonNegativeNumber);
    run->add_flag("--quiet", runQuiet, "No progress bar");
    run->add_flag("--no-preview", runNoPreview, "Do not render OUTDIR/preview.png");
    std::string runResume;
    auto* resumeOption = run->add_option("--resume", runResume, "Continue the interrupted run in this output directory from its checkpoint");
    resumeOption->excludes(run->get_option("scene"))->excludes("--seed")->excludes("--frames")->excludes("--output");

    // render
    auto* render = app.add_subcommand("render", "Render preview pictures (PNG) of a run's frames");
    std::string renderDir, renderOut, renderSize = "960x540";
    int renderFrame = -1;
    bool renderAll = false, renderSheet = false;
    render->add_option("outdir", renderDir, "A spall run's output directory")->required();
    render->add_option("--frame", renderFrame, "Frame number (default: the last)");
    render->add_flag("--all", renderAll, "Every frame");
    render->add_flag("--sheet", renderSheet, "A contact sheet of nine frames across the run");
    render->add_option("-o,--output", renderOut, "Where the pictures go (default: the output directory)");
    render->add_option("--size", renderSize, "WIDTHxHEIGHT in pixels");

    // inspect
    auto* inspect = app.add_subcommand("inspect", "Summarise a run's history.h5");
    std::string inspectPath;
    bool inspectJson = false;
    int inspectFrame = -1;
    int64_t inspectBody = -1;
    inspect->add_option("history", inspectPath, "OUTDIR/history.h5 (or OUTDIR)")->required();
    inspect->add_flag("--json", inspectJson, "JSON output");
    inspect->add_option("--frame", inspectFrame, "Frame to summarise (default: the last)");
    inspect->add_option("--body", inspectBody, "Follow one body through the run");

    // bench
    auto* bench = app.add_subcommand("bench", "Benchmarks that print tables (the micro-benchmarks are in spall_bench)");
    auto* benchCollisionsCmd = bench->add_subcommand("collisions", "Table 5-1: steps per second against boundary voxels, per method");
    bench->require_subcommand(1);
    bool benchJson = false;
    long benchMaxVoxels = 1'000'000;
    benchCollisionsCmd->add_flag("--json", benchJson, "One JSON row per method and size");
    benchCollisionsCmd->add_option("--max-boundary-voxels", benchMaxVoxels, "Largest size to run")->check(CLI::PositiveNumber);
    auto* benchAccuracyCmd = bench->add_subcommand("accuracy", "Error against a reference next to run time: CSV and log-log plots");
    std::string benchAccuracyOut = "accuracy";
    double benchSceneDuration = 0.5;
    benchAccuracyCmd->add_option("-o,--output", benchAccuracyOut, "Directory for accuracy.csv and the plots");
    benchAccuracyCmd->add_option("--scene-duration", benchSceneDuration, "Seconds of the default scene per variant (s)")
        ->check(CLI::PositiveNumber);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        if (*vox) {
            if (voxInput.empty() == voxPrimitive.empty())
                throw spall::InputError("give either a mesh file or --primitive, not both or neither");
            return runVoxelise(voxInput, voxPrimitive, voxOutput, voxSize, voxMax, voxQuiet);
        }
        if (*render) return runRender(renderDir, renderFrame, renderAll, renderSheet, renderOut, renderSize);
        if (*inspect) {
            std::string path = inspectPath;
            if (std::filesystem::is_directory(path)) path = (std::filesystem::path(path) / "history.h5").string();
            return runInspect(path, inspectJson, inspectFrame, inspectBody);
        }
        if (*run) {
            const bool resume = !runResume.empty();
            return runRun(runScenePath, resume ? runResume : runOut, resume, runThreads, runSeed, runFrames, runQuiet, !runNoPreview);
        }
        if (*blast) return runBlast(tnt, dist, burst, dataset, blastJson, curve);
        if (*benchCollisionsCmd) return spall::benchCollisions(benchJson, benchMaxVoxels);
        if (*benchAccuracyCmd) return spall::benchAccuracy(benchAccuracyOut, benchSceneDuration);
    } catch (const spall::InputError& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "spall: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}

