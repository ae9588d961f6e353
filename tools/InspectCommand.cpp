// `spall inspect`: a summary of a run's history.
#include "Commands.h"

#include <memory>

#include <spall/core/Error.h>
#include <spall/output/History.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <cstdio>
#include <cmath>
#include <iostream>

namespace {

const char* const kSizeBucketNames[] = {"1", "2-9", "10-99", "100-999", "1000-9999", ">=10000"};

/// The bucket of kSizeBucketNames a voxel count falls in: 1 alone, then decades from 2.
int sizeBucket(int64_t voxels)
{
    if (voxels <= 1) return 0;
    return std::min(5, 1 + static_cast<int>(std::floor(std::log10(double(voxels)))));
}

/// Frame f's bodies: count, mass, extremes and fragment sizes by decades of voxel count.
nlohmann::json summariseFrame(const spall::History& h, int f)
{
    const int64_t begin = h.bodyOffset[f], end = h.bodyOffset[f + 1];
    int64_t buckets[6] = {0, 0, 0, 0, 0, 0};
    double mass = 0, largest = 0, fastest = 0;
    int64_t asleep = 0, anchored = 0;
    for (int64_t i = begin; i < end; ++i) {
        buckets[sizeBucket(h.bodyVoxelCount[i])]++;
        mass += h.bodyMassKg[i];
        largest = std::max(largest, h.bodyMassKg[i]);
        fastest = std::max(fastest, h.bodyLinearVelocityMS[i].norm());
        asleep += h.bodyAsleep[i];
        anchored += h.bodyAnchored[i];
    }
    nlohmann::json sizes = nlohmann::json::object();
    for (int b = 0; b < 6; ++b) sizes[kSizeBucketNames[b]] = buckets[b];
    return {{"index", f},         {"time_s", h.timeS[f]},   {"bodies", end - begin}, {"voxels", h.voxelCount[f]},
            {"mass_kg", mass},    {"largest_fragment_kg", largest},                  {"fastest_fragment_m_s", fastest},
            {"asleep", asleep},   {"anchored", anchored},   {"kinetic_energy_J", h.kineticEnergyJ[f]},
            {"linear_momentum_kg_m_s", {h.linearMomentum[f].x(), h.linearMomentum[f].y(), h.linearMomentum[f].z()}},
            {"dust_mass_kg", h.dustMassKg[f]},              {"fragment_voxel_counts", sizes}};
}

/// The run as a whole: frames, steps, breaks, peak kinetic energy.
nlohmann::json summariseRun(const spall::History& h, const std::string& path)
{
    double maxKe = 0;
    int64_t steps = 0, broken = 0;
    for (size_t i = 0; i < h.frameCount(); ++i) {
        maxKe = std::max(maxKe, h.kineticEnergyJ[i]);
        steps += h.steps[i];
        broken += h.brokenLinks[i];
    }
    return {{"file", path},          {"run_complete", h.runComplete},  {"frames", h.frameCount()},
            {"duration_s", h.timeS.back()}, {"voxel_size_m", h.voxelSizeM}, {"seed", h.seed},
            {"steps", steps},        {"broken_links", broken},         {"fracture_events", h.eventTimeS.size()},
            {"kinetic_energy_max_J", maxKe}};
}

/// One body's rows through the run.
nlohmann::json bodyTrack(const spall::History& h, int64_t id, const std::string& path)
{
    nlohmann::json track = nlohmann::json::array();
    for (size_t i = 0; i < h.frameCount(); ++i)
        for (int64_t r = h.bodyOffset[i]; r < h.bodyOffset[i + 1]; ++r) {
            if (h.bodyId[r] != id) continue;
            const auto& p = h.bodyPositionM[r];
            track.push_back({{"frame", i}, {"time_s", h.timeS[i]}, {"position_m", {p.x(), p.y(), p.z()}},
                             {"speed_m_s", h.bodyLinearVelocityMS[r].norm()}, {"voxels", h.bodyVoxelCount[r]}, {"asleep", h.bodyAsleep[r] != 0}});
        }
    if (track.empty()) throw spall::InputError(path + ": --body " + std::to_string(id) + " does not appear in any frame");
    return {{"id", id}, {"track", track}};
}

/// The summary as text, read from the JSON so both forms say the same.
void printSummary(const nlohmann::json& j)
{
    const nlohmann::json& f = j["frame"];
    std::printf("%s: %d frames over %.3f s (%s), voxel size %g m, seed %llu\n", j["file"].get<std::string>().c_str(), j["frames"].get<int>(),
                j["duration_s"].get<double>(), j["run_complete"].get<bool>() ? "complete" : "INCOMPLETE: the run was interrupted",
                j["voxel_size_m"].get<double>(), j["seed"].get<unsigned long long>());
    std::printf("  %lld steps, %lld links broken, %lld fracture events, peak kinetic energy %.4g J\n", j["steps"].get<long long>(),
                j["broken_links"].get<long long>(), j["fracture_events"].get<long long>(), j["kinetic_energy_max_J"].get<double>());
    std::printf("frame %d (t = %.3f s): %lld bodies (%lld asleep, %lld anchored), %lld voxels, %.4g kg\n", f["index"].get<int>(),
                f["time_s"].get<double>(), f["bodies"].get<long long>(), f["asleep"].get<long long>(), f["anchored"].get<long long>(),
                f["voxels"].get<long long>(), f["mass_kg"].get<double>());
    std::printf("  largest fragment %.4g kg, fastest %.3g m/s, kinetic energy %.4g J, dust %.4g kg\n", f["largest_fragment_kg"].get<double>(),
                f["fastest_fragment_m_s"].get<double>(), f["kinetic_energy_J"].get<double>(), f["dust_mass_kg"].get<double>());
    const nlohmann::json& p = f["linear_momentum_kg_m_s"];
    std::printf("  linear momentum (%.4g, %.4g, %.4g) kg m/s\n", p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
    std::printf("  fragments by voxel count:");
    for (const char* name : kSizeBucketNames)
        if (f["fragment_voxel_counts"][name].get<long long>()) std::printf("  %s: %lld", name, f["fragment_voxel_counts"][name].get<long long>());
    std::printf("\n");
    if (!j.contains("body")) return;
    std::printf("body %lld:\n", j["body"]["id"].get<long long>());
    for (const auto& row : j["body"]["track"])
        std::printf("  frame %4d  t %.3f s  position (%.3f, %.3f, %.3f) m  speed %.3f m/s%s\n", row["frame"].get<int>(),
                    row["time_s"].get<double>(), row["position_m"][0].get<double>(), row["position_m"][1].get<double>(),
                    row["position_m"][2].get<double>(), row["speed_m_s"].get<double>(), row["asleep"].get<bool>() ? "  asleep" : "");
}

int runInspect(const std::string& path, bool json, int frameArg, int64_t bodyArg)
{
    const spall::History h = spall::readHistory(path);
    const int frames = static_cast<int>(h.frameCount());
    if (frames == 0) throw spall::InputError(path + ": the history holds no frames");
    if (frameArg >= frames || frameArg < -1)
        throw spall::InputError(path + ": --frame " + std::to_string(frameArg) + " does not exist (frames 0.." + std::to_string(frames - 1) + ")");
    nlohmann::json j = summariseRun(h, path);
    j["frame"] = summariseFrame(h, frameArg >= 0 ? frameArg : frames - 1);
    if (bodyArg >= 0) j["body"] = bodyTrack(h, bodyArg, path);
    if (json)
        std::cout << j.dump(2) << "\n";
    else
        printSummary(j);
    return 0;
}

}  // namespace

void addInspectCommand(CLI::App& app, CommandAction& action)
{
    struct Options {
        std::string path;
        bool json = false;
        int frame = -1;
        int64_t body = -1;
    };
    auto o = std::make_shared<Options>();
    auto* sub = app.add_subcommand("inspect", "Summarise a run's history.h5");
    sub->add_option("history", o->path, "OUTDIR/history.h5 (or OUTDIR)")->required();
    sub->add_flag("--json", o->json, "JSON output");
    sub->add_option("--frame", o->frame, "Frame to summarise (default: the last)");
    sub->add_option("--body", o->body, "Follow one body through the run");
    sub->callback([o, &action] {
        action = [o] {
            std::string path = o->path;
            if (std::filesystem::is_directory(path)) path = (std::filesystem::path(path) / "history.h5").string();
            return runInspect(path, o->json, o->frame, o->body);
        };
    });
}
