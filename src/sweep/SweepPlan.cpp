#include <spall/sweep/Sweep.h>

#include <spall/core/AtomicFile.h>
#include <spall/core/EnumNames.h>
#include <spall/scene/Scene.h>
#include <spall/run/Run.h>
#include <spall/voxel/Voxelise.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace spall {

namespace {

constexpr const char* kManifestName = "sweep.json";
constexpr int kManifestVersion = 1;

/// The value at a key path (`charges[0].tnt_kg`), created when an object lacks the key; an index
/// past an array's end is an error naming the path.
nlohmann::json& valueAtPath(nlohmann::json& root, const std::string& path)
{
    nlohmann::json* node = &root;
    std::stringstream segments(path);
    std::string segment;
    while (std::getline(segments, segment, '.')) {
        const size_t bracket = segment.find('[');
        const std::string name = segment.substr(0, bracket);
        if (name.empty() && bracket == 0 && node == &root) throw InputError(path + ": a key path starts with a key");
        if (!name.empty()) {
            if (!node->is_object()) throw InputError(path + ": " + name + " is not inside an object");
            node = &(*node)[name];
        }
        for (size_t at = bracket; at != std::string::npos; at = segment.find('[', at + 1)) {
            const size_t close = segment.find(']', at);
            if (close == std::string::npos) throw InputError(path + ": unclosed [");
            const size_t index = std::stoul(segment.substr(at + 1, close - at - 1));
            if (!node->is_array() || index >= node->size())
                throw InputError(path + ": the scene has no " + segment.substr(0, close + 1) + " (it lists " +
                                 std::to_string(node->is_array() ? node->size() : 0) + ")");
            node = &(*node)[index];
        }
    }
    return *node;
}

nlohmann::json parseValue(const std::string& text)
{
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error&) {
        return text;  // a bare word: a string such as a material name
    }
}

void writeJson(const std::string& path, const nlohmann::json& json)
{
    writeFileAtomically(path, [&](std::ostream& out) { out << json.dump(2) << "\n"; });
}

nlohmann::json readJson(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw InputError(path + ": missing");
    try {
        return nlohmann::json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(path + ": not JSON (" + e.what() + ")");
    }
}

void writeStatus(const std::string& dir, VariantState state, const std::string& message)
{
    writeJson(dir + "/status.json", {{"state", enumName(state)}, {"message", message}});
}

}  // namespace

SweepAxis parseSweepAxis(const std::string& text)
{
    const size_t equals = text.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == text.size())
        throw InputError("--vary " + text + ": expected KEY=V1,V2,...");
    SweepAxis axis{text.substr(0, equals), {}};
    std::stringstream values(text.substr(equals + 1));
    std::string value;
    while (std::getline(values, value, ',')) axis.values.push_back(parseValue(value));
    return axis;
}

std::string SweepVariant::name() const
{
    char s[16];
    std::snprintf(s, sizeof s, "v%04d", index);
    return s;
}

std::string SweepVariant::overridesText() const
{
    std::string text;
    for (const auto& [key, value] : overrides) text += (text.empty() ? "" : ";") + key + "=" + value.dump();
    return text;
}

nlohmann::json variantScene(const SweepPlan& plan, const SweepVariant& variant)
{
    nlohmann::json scene = plan.scene;
    for (const auto& [key, value] : variant.overrides) valueAtPath(scene, key) = value;
    scene["seed"] = variant.seed;
    return scene;
}

SweepPlan planSweep(const std::string& scenePath, const std::vector<SweepAxis>& axes, int seeds)
{
    SweepPlan plan;
    plan.scenePath = fs::absolute(scenePath).lexically_normal().string();
    plan.sceneDirectory = fs::path(plan.scenePath).parent_path().string();
    plan.scene = readJson(plan.scenePath);
    plan.axes = axes;
    plan.seeds = seeds;
    const uint64_t baseSeed = loadScene(plan.scenePath).seed;
    size_t combinations = 1;
    for (const SweepAxis& axis : axes) combinations *= axis.values.size();
    for (size_t c = 0; c < combinations; ++c)
        for (int s = 0; s < std::max(1, seeds); ++s) {
            SweepVariant v;
            v.index = static_cast<int>(plan.variants.size());
            v.seed = baseSeed + static_cast<uint64_t>(s);
            for (size_t a = 0, rest = c; a < axes.size(); ++a) {
                size_t stride = 1;
                for (size_t b = a + 1; b < axes.size(); ++b) stride *= axes[b].values.size();
                v.overrides.push_back({axes[a].key, axes[a].values[rest / stride]});
                rest %= stride;
            }
            try {
                parseScene(variantScene(plan, v).dump(), plan.scenePath, plan.sceneDirectory);
            } catch (const InputError& e) {
                throw InputError("sweep variant " + v.name() + " (" + v.overridesText() + "): " + e.what());
            }
            plan.variants.push_back(std::move(v));
        }
    return plan;
}

void writeSweepPlan(const std::string& sweepDir, const SweepPlan& plan)
{
    nlohmann::json variants = nlohmann::json::array();
    for (const SweepVariant& v : plan.variants) {
        nlohmann::json overrides = nlohmann::json::array();
        for (const auto& [key, value] : v.overrides) overrides.push_back({key, value});
        variants.push_back({{"index", v.index}, {"name", v.name()}, {"seed", v.seed}, {"overrides", overrides}});
    }
    nlohmann::json axes = nlohmann::json::array();
    for (const SweepAxis& a : plan.axes) axes.push_back({{"key", a.key}, {"values", a.values}});
    writeJson(sweepDir + "/" + kManifestName, {{"format", "spall-sweep"}, {"format_version", kManifestVersion}, {"scene_path", plan.scenePath},
                                               {"scene_directory", plan.sceneDirectory}, {"scene", plan.scene}, {"axes", axes},
                                               {"seeds", plan.seeds}, {"variants", variants}});
}

SweepPlan readSweepPlan(const std::string& sweepDir)
{
    const std::string path = sweepDir + "/" + kManifestName;
    const nlohmann::json j = readJson(path);
    if (j.value("format", "") != "spall-sweep" || j.value("format_version", 0) != kManifestVersion)
        throw InputError(path + ": not a spall sweep manifest of format version " + std::to_string(kManifestVersion));
    SweepPlan plan;
    plan.scenePath = j.at("scene_path");
    plan.sceneDirectory = j.at("scene_directory");
    plan.scene = j.at("scene");
    plan.seeds = j.at("seeds");
    for (const auto& a : j.at("axes")) plan.axes.push_back({a.at("key"), a.at("values").get<std::vector<nlohmann::json>>()});
    for (const auto& v : j.at("variants")) {
        SweepVariant variant;
        variant.index = v.at("index");
        variant.seed = v.at("seed");
        for (const auto& o : v.at("overrides")) variant.overrides.push_back({o.at(0), o.at(1)});
        plan.variants.push_back(std::move(variant));
    }
    return plan;
}

bool samePlan(const SweepPlan& a, const SweepPlan& b)
{
    const auto axes = [](const SweepPlan& p) {
        nlohmann::json j = nlohmann::json::array();
        for (const SweepAxis& axis : p.axes) j.push_back({axis.key, axis.values});
        return j;
    };
    return a.scene == b.scene && a.seeds == b.seeds && axes(a) == axes(b) && a.variants.size() == b.variants.size();
}

std::string variantDirectory(const std::string& sweepDir, const SweepVariant& variant) { return sweepDir + "/variants/" + variant.name(); }

std::string variantOutputDirectory(const std::string& sweepDir, const SweepVariant& variant)
{
    return variantDirectory(sweepDir, variant) + "/out";
}

VariantStatus readVariantStatus(const std::string& sweepDir, const SweepVariant& variant)
{
    const std::string path = variantDirectory(sweepDir, variant) + "/status.json";
    if (!fs::exists(path)) return {};
    const nlohmann::json j = readJson(path);
    return {parseEnum<VariantState>(j.value("state", "pending")), j.value("message", "")};
}

namespace {

RunReport runOrResume(const std::string& out, const SweepPlan& plan, const SweepVariant& v, Interrupter* interrupter)
{
    RunOptions options;
    options.outputDirectory = out;
    options.interrupter = interrupter;
    // The variant's directory is the sweep's: what an attempt that failed before its history
    // left there is replaced.
    options.replaceEarlierRun = true;
    const auto onFrame = [interrupter](const RunProgress&) { return !(interrupter && interrupter->wasInterrupted(0)); };
    if (fs::exists(out + "/history.h5")) {
        if (readHistory(out + "/history.h5").runComplete) {
            RunReport finished;
            finished.complete = true;
            return finished;
        }
        return resumeRun(options, onFrame);
    }
    return runScene(parseScene(variantScene(plan, v).dump(), plan.scenePath + " (" + v.name() + ")", plan.sceneDirectory), options, onFrame);
}

}  // namespace

VariantState runSweepVariant(const std::string& sweepDir, const SweepPlan& plan, int index, Interrupter* interrupter)
{
    if (index < 0 || index >= static_cast<int>(plan.variants.size()))
        throw InputError("sweep variant " + std::to_string(index) + ": the sweep has " + std::to_string(plan.variants.size()) + " variants");
    const SweepVariant& v = plan.variants[index];
    const std::string dir = variantDirectory(sweepDir, v), out = variantOutputDirectory(sweepDir, v);
    fs::create_directories(dir);
    writeJson(dir + "/scene.json", variantScene(plan, v));
    try {
        if (!runOrResume(out, plan, v, interrupter).complete) {
            writeStatus(dir, VariantState::Stopped, "stopped on request; the next sweep run resumes it from its checkpoint");
            return VariantState::Stopped;
        }
        writeDebrisReport(out, analyseDebris(readHistory(out + "/history.h5")));
    } catch (const VoxeliseInterrupted&) {
        writeStatus(dir, VariantState::Stopped, "stopped on request while voxelising; the next sweep run starts it again");
        return VariantState::Stopped;
    } catch (const std::exception& e) {
        writeStatus(dir, VariantState::Failed, e.what());
        return VariantState::Failed;
    }
    writeStatus(dir, VariantState::Done, "");
    return VariantState::Done;
}

}  // namespace spall
