// `spall inspect`: a summary of a run's history.
#include "Commands.h"

#include <memory>

#include <spall/core/Error.h>
#include <spall/io/History.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <map>

namespace {


int runInspect(const std::string& path, bool json, int frameArg, int64_t bodyArg)
{
    const spall::History h = spall::readHistory(path);
    const int frames = static_cast<int>(h.frameCount());
    if (frames == 0) throw spall::InputError(path + ": the history holds no frames");
    if (frameArg >= frames || frameArg < -1)
        throw spall::InputError(path + ": --frame " + std::to_string(frameArg) + " does not exist (frames 0.." + std::to_string(frames - 1) + ")");
    const int f = frameArg >= 0 ? frameArg : frames - 1;
    const int64_t begin = h.bodyOffset[f], end = h.bodyOffset[f + 1];

    // Fragment sizes of the frame, by decades of voxel count.
    const char* bucketNames[] = {"1", "2-9", "10-99", "100-999", "1000-9999", ">=10000"};
    int64_t buckets[6] = {0, 0, 0, 0, 0, 0};
    double mass = 0, largest = 0, fastest = 0;
    int64_t asleep = 0, anchored = 0;
    for (int64_t i = begin; i < end; ++i) {
        const int64_t v = h.bodyVoxelCount[i];
        buckets[std::min(5, static_cast<int>(std::floor(std::log10(double(v)))))]++;
        mass += h.bodyMassKg[i];
        largest = std::max(largest, h.bodyMassKg[i]);
        fastest = std::max(fastest, h.bodyLinearVelocityMS[i].norm());
        asleep += h.bodyAsleep[i];
        anchored += h.bodyAnchored[i];
    }
    double maxKe = 0;
    int64_t steps = 0, broken = 0;
    for (int i = 0; i < frames; ++i) {
        maxKe = std::max(maxKe, h.kineticEnergyJ[i]);
        steps += h.steps[i];
        broken += h.brokenLinks[i];
    }
    nlohmann::json j;
    j["file"] = path;
    j["run_complete"] = h.runComplete;
    j["frames"] = frames;
    j["duration_s"] = h.timeS.back();
    j["voxel_size_m"] = h.voxelSizeM;
    j["seed"] = h.seed;
    j["steps"] = steps;
    j["broken_links"] = broken;
    j["fracture_events"] = h.eventTimeS.size();
    j["kinetic_energy_max_J"] = maxKe;
    j["frame"] = {{"index", f},
                  {"time_s", h.timeS[f]},
                  {"bodies", end - begin},
                  {"voxels", h.voxelCount[f]},
                  {"mass_kg", mass},
                  {"largest_fragment_kg", largest},
                  {"fastest_fragment_m_s", fastest},
                  {"asleep", asleep},
                  {"anchored", anchored},
                  {"kinetic_energy_J", h.kineticEnergyJ[f]},
                  {"linear_momentum_kg_m_s", {h.linearMomentum[f].x(), h.linearMomentum[f].y(), h.linearMomentum[f].z()}},
                  {"dust_mass_kg", h.dustMassKg[f]}};
    nlohmann::json sizes = nlohmann::json::object();
    for (int b = 0; b < 6; ++b) sizes[bucketNames[b]] = buckets[b];
    j["frame"]["fragment_voxel_counts"] = sizes;
    if (bodyArg >= 0) {
        nlohmann::json track = nlohmann::json::array();
        for (int i = 0; i < frames; ++i)
            for (int64_t r = h.bodyOffset[i]; r < h.bodyOffset[i + 1]; ++r)
                if (h.bodyId[r] == bodyArg) {
                    const auto& p = h.bodyPositionM[r];
                    const auto& v = h.bodyLinearVelocityMS[r];
                    track.push_back({{"frame", i}, {"time_s", h.timeS[i]}, {"position_m", {p.x(), p.y(), p.z()}},
                                     {"speed_m_s", v.norm()}, {"voxels", h.bodyVoxelCount[r]}, {"asleep", h.bodyAsleep[r] != 0}});
                }
        if (track.empty()) throw spall::InputError(path + ": --body " + std::to_string(bodyArg) + " does not appear in any frame");
        j["body"] = {{"id", bodyArg}, {"track", track}};
    }
    if (json) {
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::printf("%s: %d frames over %.3f s (%s), voxel size %g m, seed %llu\n", path.c_str(), frames, h.timeS.back(),
                h.runComplete ? "complete" : "INCOMPLETE: the run was interrupted", h.voxelSizeM, (unsigned long long)h.seed);
    std::printf("  %lld steps, %lld links broken, %zu fracture events, peak kinetic energy %.4g J\n", (long long)steps,
                (long long)broken, h.eventTimeS.size(), maxKe);
    std::printf("frame %d (t = %.3f s): %lld bodies (%lld asleep, %lld anchored), %lld voxels, %.4g kg\n", f, h.timeS[f],
                (long long)(end - begin), (long long)asleep, (long long)anchored, (long long)h.voxelCount[f], mass);
    std::printf("  largest fragment %.4g kg, fastest %.3g m/s, kinetic energy %.4g J, dust %.4g kg\n", largest, fastest,
                h.kineticEnergyJ[f], h.dustMassKg[f]);
    std::printf("  linear momentum (%.4g, %.4g, %.4g) kg m/s\n", h.linearMomentum[f].x(), h.linearMomentum[f].y(), h.linearMomentum[f].z());
    std::printf("  fragments by voxel count:");
    for (int b = 0; b < 6; ++b)
        if (buckets[b]) std::printf("  %s: %lld", bucketNames[b], (long long)buckets[b]);
    std::printf("\n");
    if (j.contains("body")) {
        std::printf("body %lld:\n", (long long)bodyArg);
        for (const auto& row : j["body"]["track"])
            std::printf("  frame %4d  t %.3f s  position (%.3f, %.3f, %.3f) m  speed %.3f m/s%s\n", row["frame"].get<int>(),
                        row["time_s"].get<double>(), row["position_m"][0].get<double>(), row["position_m"][1].get<double>(),
                        row["position_m"][2].get<double>(), row["speed_m_s"].get<double>(), row["asleep"].get<bool>() ? "  asleep" : "");
    }
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
