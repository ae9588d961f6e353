// Sweeps: one scene run many times, over seeds and over values of its keys, each variant a
// `spall run` of its own, then one summary of the debris figures across variants
// (docs/sweeps.md). Scheduling (local processes, a Slurm job array) is the command line's; this
// is the plan, a variant's run, and the summary.
#pragma once

#include <spall/analysis/Debris.h>
#include <spall/core/EnumNames.h>
#include <spall/core/Error.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace spall {

/// One key the sweep varies, as `KEY=V1,V2,...` on the command line. Keys are scene key paths as
/// error messages print them (`charges[0].tnt_kg`, `solver.max_time_step_s`); values parse as
/// JSON, or are taken as strings (`brick-masonry`).
struct SweepAxis {
    std::string key;
    std::vector<nlohmann::json> values;
};
SweepAxis parseSweepAxis(const std::string& text);

struct SweepVariant {
    int index = 0;
    uint64_t seed = 0;
    std::vector<std::pair<std::string, nlohmann::json>> overrides;  ///< in axis order
    std::string name() const;          ///< v0000, v0001, ...
    std::string overridesText() const;  ///< key=value;key=value
};

/// The manifest: the base scene and every variant, saved as DIR/sweep.json.
struct SweepPlan {
    std::string scenePath;       ///< absolute
    std::string sceneDirectory;  ///< where its relative mesh paths resolve
    nlohmann::json scene;        ///< as the file holds it
    std::vector<SweepAxis> axes;
    int seeds = 0;               ///< 0: every variant keeps the scene's seed
    std::vector<SweepVariant> variants;
};

/// Every combination of the axes' values (first axis slowest), each with `seeds` seeds (the
/// scene's seed + 0 … seeds − 1; none given: the scene's own). Each variant's scene is parsed
/// here, so a bad key or value is an InputError naming the variant and the key before anything
/// runs.
SweepPlan planSweep(const std::string& scenePath, const std::vector<SweepAxis>& axes, int seeds);

/// The variant's scene: the base with its overrides and seed.
nlohmann::json variantScene(const SweepPlan& plan, const SweepVariant& variant);

void writeSweepPlan(const std::string& sweepDir, const SweepPlan& plan);
/// Throws InputError naming DIR/sweep.json when it is missing or not a sweep manifest.
SweepPlan readSweepPlan(const std::string& sweepDir);
/// Same base scene, axes and seeds.
bool samePlan(const SweepPlan& a, const SweepPlan& b);

/// Where a variant's files are: DIR/variants/vNNNN/{scene.json, out/, status.json}.
std::string variantDirectory(const std::string& sweepDir, const SweepVariant& variant);
std::string variantOutputDirectory(const std::string& sweepDir, const SweepVariant& variant);

enum class VariantState { Pending, Done, Stopped, Failed };
template <>
struct EnumNames<VariantState> {
    static constexpr std::pair<VariantState, const char*> kNames[] = {
        {VariantState::Pending, "pending"}, {VariantState::Done, "done"}, {VariantState::Stopped, "stopped"}, {VariantState::Failed, "failed"}};
};
struct VariantStatus {
    VariantState state = VariantState::Pending;
    std::string message;
};
VariantStatus readVariantStatus(const std::string& sweepDir, const SweepVariant& variant);

/// Runs one variant in this process: resumes its run when one was started, runs its debris
/// analysis, and records the outcome in its status.json (done; stopped on a stop request, with a
/// checkpoint to resume from; failed with the error's message). Returns the state.
VariantState runSweepVariant(const std::string& sweepDir, const SweepPlan& plan, int index, Interrupter* interrupter);

/// The figures of one variant that the summary compares.
struct VariantFigures {
    int64_t fragments = 0, hazardous = 0;
    double maxThrowDistanceM = 0, medianThrowDistanceM = 0, hazardousFragmentDistanceM = 0, worstSectorHazardousFragmentDistanceM = 0;
    double weibullShape = 0;
};

/// Mean and a 95 % confidence interval of the mean (Student's t on n − 1 degrees of freedom).
struct MeanInterval {
    int64_t n = 0;
    double mean = 0, halfWidth = 0, min = 0, max = 0;
};
MeanInterval meanInterval(const std::vector<double>& values);

struct SweepSummary {
    std::vector<VariantStatus> status;   ///< per variant
    std::vector<VariantFigures> figures;  ///< per variant (zero unless done)
    /// Variants sharing their overrides (they differ in seed only), in order of first appearance.
    std::vector<std::vector<int>> groups;
};

/// Whether a group's seeds changed any figure: false when two or more of its variants finished
/// and all gave the same figures (nothing in the scene draws on the seed, e.g. no material scatters).
bool seedsChangedAnything(const SweepSummary& summary, const std::vector<int>& group);

/// Reads every variant's status and history (DIR/variants/...); a failed or unfinished variant
/// is reported as such and leaves the others' figures alone.
SweepSummary collectSweep(const std::string& sweepDir, const SweepPlan& plan);

/// DIR/summary.h5, summary.csv (a row per variant), summary_groups.csv (mean and interval of each
/// figure per group) and summary_hfd.png (the hazardous fragment distance over seeds).
void writeSweepSummary(const std::string& sweepDir, const SweepPlan& plan, const SweepSummary& summary);

}  // namespace spall
