// `spall loads OUTDIR|SCENE`: the blast's peak pressure and impulse on every face of the
// scene's objects as they stood, held still, and the front face against the blast data's
// normally reflected values (loads.h5, loads.vdb, loads_front.png; docs/loads.md).
#include "Commands.h"

#include <spall/analysis/StructureLoads.h>
#include <spall/scene/Scene.h>
#include <spall/voxel/LinkBits.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace fs = std::filesystem;

namespace {

void printObject(const spall::ObjectLoads& object, const spall::Scene& scene)
{
    const spall::FrontFace& front = object.front;
    const char* names[] = {"-x", "+x", "-y", "+y", "-z", "+z"};
    std::printf("%s: front face %s (%zu voxel faces): impulse mean %.4g Pa s, max %.4g Pa s; peak pressure max %.4g kPa; "
                "net impulse (%.4g, %.4g, %.4g) N s\n",
                object.name.c_str(), names[front.face], front.faces, front.meanImpulsePaS, front.maxImpulsePaS, front.maxPeakPressurePa / 1e3,
                object.netImpulseNS.x(), object.netImpulseNS.y(), object.netImpulseNS.z());
    if (front.faces == 0) return;
    const spall::FaceLoad& nearest = object.faces[front.nearest];
    const bool surface = scene.charges.at(front.charge).burst == spall::BurstType::Surface;
    std::printf("  nearest charge %d: %.3g m, Z %.3g m/kg^(1/3), %.1f deg off normal: impulse %.4g Pa s against the blast data's "
                "normally reflected Ir %.4g Pa s (%+.1f %%), peak %.4g kPa against Pr %.4g kPa (%+.1f %%), %s\n",
                front.charge, front.distanceM, front.scaledDistanceMKg13, std::acos(std::clamp(front.cosIncidence, -1.0, 1.0)) * 180 / M_PI,
                nearest.impulsePaS, front.reflectedImpulsePaS, 100 * (nearest.impulsePaS / front.reflectedImpulsePaS - 1),
                nearest.peakPressurePa / 1e3, front.reflectedPressurePa / 1e3, 100 * (nearest.peakPressurePa / front.reflectedPressurePa - 1),
                surface ? "surface burst (free air, twice the mass)"
                        : scene.world.ground.enabled ? "free-air burst, direct wave only (its reflection from the ground adds to the face's)"
                                                     : "free-air burst");
}

int loadsCommand(const std::string& source, std::string outDir, bool quiet)
{
    if (!fs::exists(source)) throw spall::InputError(source + ": no such run directory or scene file");
    const bool isRun = fs::is_directory(source);
    const std::string scenePath = isRun ? (fs::path(source) / "scene.json").string() : source;
    if (outDir.empty()) outDir = isRun ? source : fs::path(source).parent_path().string();
    if (outDir.empty()) outDir = ".";
    if (!fs::is_directory(outDir)) throw spall::InputError(outDir + ": no such directory for the loads");
    const spall::Simulation simulation(spall::loadScene(scenePath));
    const auto progress = [quiet](int64_t done, int64_t total) {
        if (quiet || done * 10 / total == (done - 1) * 10 / total) return;
        std::fprintf(stderr, "spall loads: %lld %% of %lld steps\n", static_cast<long long>(done * 100 / total), static_cast<long long>(total));
    };
    const spall::StructureLoadsReport report = spall::structureLoads(simulation, progress);
    for (const spall::ObjectLoads& object : report.objects) printObject(object, simulation.scene());
    spall::writeStructureLoads(outDir, report);
    std::printf("%lld steps of %.3g us to %.4g s; wrote %s/loads.h5, loads.vdb, loads_front.png\n", static_cast<long long>(report.steps),
                report.timeStepS * 1e6, report.endTimeS, outDir.c_str());
    return 0;
}

}  // namespace

void addLoadsCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string source, output;
        bool quiet = false;
    };
    auto o = std::make_shared<Options>();
    auto* loads = app.add_subcommand("loads", "The blast's peak pressure and impulse on every face of the objects as they stood, held still");
    loads->add_option("source", o->source, "A run's output directory (its scene.json) or a scene file")->required();
    loads->add_option("-o,--output", o->output, "Directory to write into (default: the run's directory, or the scene file's)");
    loads->add_flag("--quiet", o->quiet, "No progress");
    loads->callback([o, &action] { action = [o] { return loadsCommand(o->source, o->output, o->quiet); }; });
}
