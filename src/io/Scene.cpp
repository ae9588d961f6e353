#include <spall/io/Scene.h>

#include <spall/core/Error.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace spall {

namespace {

using nlohmann::json;

/// Reads one JSON object strictly: every key must be read, types must match, values must pass
/// their checks; errors name the file, the key path and the reason.
class ObjectReader {
public:
    ObjectReader(const json& value, std::string file, std::string path)
        : mValue(value), mFile(std::move(file)), mPath(std::move(path))
    {
        if (!mValue.is_object()) fail(mPath, "must be a JSON object");
    }

    [[noreturn]] void fail(const std::string& key, const std::string& reason) const
    {
        throw InputError(mFile + ": " + (key.empty() ? "(top level)" : key) + ": " + reason);
    }
    std::string keyPath(const std::string& key) const { return mPath.empty() ? key : mPath + "." + key; }
    bool has(const std::string& key) const { return mValue.contains(key); }

    const json* raw(const std::string& key)
    {
        mUsed.insert(key);
        auto it = mValue.find(key);
        return it == mValue.end() ? nullptr : &*it;
    }

    double number(const std::string& key, double fallback, double lo, double hi, bool openLo = false)
    {
        const json* v = raw(key);
        if (!v) return fallback;
        if (!v->is_number()) fail(keyPath(key), "must be a number, got " + std::string(v->type_name()));
        const double x = v->get<double>();
        if (!std::isfinite(x) || x < lo || x > hi || (openLo && x == lo)) {
            std::ostringstream msg;
            msg << "must be in " << (openLo ? "(" : "[") << lo << ", " << hi << "], got " << x;
            fail(keyPath(key), msg.str());
        }
        return x;
    }
    int64_t integer(const std::string& key, int64_t fallback, int64_t lo, int64_t hi)
    {
        const json* v = raw(key);
        if (!v) return fallback;
        if (!v->is_number_integer()) fail(keyPath(key), "must be an integer");
        const int64_t x = v->get<int64_t>();
        if (x < lo || x > hi) fail(keyPath(key), "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(x));
        return x;
    }
    bool boolean(const std::string& key, bool fallback)
    {
        const json* v = raw(key);
        if (!v) return fallback;
        if (!v->is_boolean()) fail(keyPath(key), "must be true or false");
        return v->get<bool>();
    }
    std::string string(const std::string& key, const std::string& fallback)
    {
        const json* v = raw(key);
        if (!v) return fallback;
        if (!v->is_string()) fail(keyPath(key), "must be a string");
        return v->get<std::string>();
    }
    Eigen::Vector3d vector3(const std::string& key, const Eigen::Vector3d& fallback)
    {
        const json* v = raw(key);
        if (!v) return fallback;
        if (!v->is_array() || v->size() != 3) fail(keyPath(key), "must be an array of 3 numbers");
        Eigen::Vector3d out;
        for (int i = 0; i < 3; ++i) {
            if (!(*v)[i].is_number() || !std::isfinite((*v)[i].get<double>())) fail(keyPath(key), "must be an array of 3 finite numbers");
            out[i] = (*v)[i].get<double>();
        }
        return out;
    }
    /// Calls `parse` with a reader for a nested object, if present.
    template <typename F>
    void object(const std::string& key, F&& parse)
    {
        const json* v = raw(key);
        if (!v) return;
        ObjectReader child(*v, mFile, keyPath(key));
        parse(child);
        child.finish();
    }
    template <typename F>
    void array(const std::string& key, F&& parse)
    {
        const json* v = raw(key);
        if (!v) return;
        if (!v->is_array()) fail(keyPath(key), "must be an array");
        for (size_t i = 0; i < v->size(); ++i) {
            ObjectReader child((*v)[i], mFile, keyPath(key) + "[" + std::to_string(i) + "]");
            parse(child, i);
            child.finish();
        }
    }
    /// Every key of this object not read is unknown.
    void finish() const
    {
        // Keys that were renamed, with what replaced them.
        static const std::map<std::string, std::string> renamed = {
            {"checkpoint_every_frames", "output.checkpoint_every_s (wall-clock seconds between checkpoints)"}};
        for (auto it = mValue.begin(); it != mValue.end(); ++it) {
            if (mUsed.count(it.key())) continue;
            const auto r = renamed.find(it.key());
            fail(keyPath(it.key()), r == renamed.end() ? "unknown key" : "unknown key, replaced by " + r->second);
        }
    }
    const std::string& file() const { return mFile; }

    /// Turns a library InputError about a value into one naming this key.
    template <typename F>
    auto checked(const std::string& key, F&& f) -> decltype(f())
    {
        try {
            return f();
        } catch (const InputError& e) {
            fail(keyPath(key), e.what());
        }
    }

private:
    const json& mValue;
    std::string mFile;
    std::string mPath;
    std::set<std::string> mUsed;
};

constexpr double kHuge = 1e12;

Material parseMaterial(ObjectReader& r, const std::string& name, const Material& base)
{
    Material m = base;
    m.name = name;
    m.densityKgM3 = r.number("density_kg_m3", m.densityKgM3, 0, kHuge, true);
    m.meanYieldPa = r.number("mean_yield_Pa", m.meanYieldPa, 0, kHuge, true);
    m.yieldVariation = r.number("yield_variation", m.yieldVariation, 0, 0.999);
    m.weakeningFraction = r.number("weakening_fraction", m.weakeningFraction, 0, 0.999);
    m.orientationFactor = r.number("orientation_factor", m.orientationFactor, 0, 0.999);
    m.damageRatePerS = r.number("damage_rate_per_s", m.damageRatePerS, 0, kHuge);
    m.damageStressScalePerPa = r.number("damage_stress_scale_per_Pa", m.damageStressScalePerPa, 0, kHuge);
    m.source = "scene " + r.file();
    return m;
}

}  // namespace

const Material& Scene::material(const std::string& name) const
{
    for (const Material& m : materials)
        if (m.name == name) return m;
    return findMaterialPreset(name);
}

Eigen::Quaterniond rotationFromDegrees(const Eigen::Vector3d& deg)
{
    const double k = M_PI / 180.0;
    return Eigen::AngleAxisd(deg.z() * k, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(deg.y() * k, Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(deg.x() * k, Eigen::Vector3d::UnitX());
}

const char* defaultSceneJson()
{
    return R"({
  "voxel_size_m": 0.1,
  "duration_s": 4.0,
  "frame_rate_hz": 24,
  "seed": 7,
  "objects": [
    {
      "name": "wall",
      "primitive": {"shape": "box", "size_m": [4.0, 0.3, 2.5]},
      "position_m": [0.0, 0.0, 1.25],
      "material": "brick-masonry",
      "anchor": "ground"
    }
  ],
  "charges": [
    {"position_m": [0.3, -4.0, 0.0], "tnt_kg": 20.0, "detonation_time_s": 0.0, "burst": "surface"}
  ]
}
)";
}

Scene parseScene(const std::string& text, const std::string& sourceName, const std::string& baseDirectory)
{
    json root;
    try {
        root = json::parse(text);
    } catch (const json::exception& e) {
        // parse_error, and out_of_range for numbers beyond a double (found by fuzz/fuzz_scene).
        throw InputError(sourceName + ": not valid JSON: " + e.what());
    }
    Scene scene;
    scene.sourceName = sourceName;
    scene.materials = materialPresets();
    ObjectReader r(root, sourceName, "");
    scene.voxelSizeM = r.number("voxel_size_m", scene.voxelSizeM, 0, 100, true);
    scene.durationS = r.number("duration_s", scene.durationS, 0, 1e5);
    scene.frameRateHz = r.number("frame_rate_hz", scene.frameRateHz, 0, 1e4, true);
    scene.seed = static_cast<uint64_t>(r.integer("seed", static_cast<int64_t>(scene.seed), 0, INT64_MAX));
    scene.maxVoxels = r.integer("max_voxels", scene.maxVoxels, 1, INT64_MAX);
    scene.world.gravityMS2 = r.vector3("gravity_m_s2", scene.world.gravityMS2);
    r.object("atmosphere", [&](ObjectReader& a) {
        scene.blast.atmosphere.pressurePa = a.number("pressure_Pa", scene.blast.atmosphere.pressurePa, 0, 1e8, true);
        scene.blast.atmosphere.temperatureK = a.number("temperature_K", scene.blast.atmosphere.temperatureK, 0, 1e4, true);
    });
    r.object("ground", [&](ObjectReader& g) {
        GroundPlane& ground = scene.world.ground;
        ground.enabled = g.boolean("enabled", ground.enabled);
        const Eigen::Vector3d n = g.vector3("normal", ground.normal);
        if (!(n.norm() > 0)) g.fail(g.keyPath("normal"), "must not be zero");
        ground.normal = n.normalized();
        ground.offsetM = g.number("height_m", ground.offsetM, -1e6, 1e6);
        ground.restitution = g.number("restitution", ground.restitution, 0, 1);
        ground.friction = g.number("friction", ground.friction, 0, 100);
    });
    r.array("colliders", [&](ObjectReader& c, size_t) {
        StaticBox box;
        box.centreM = c.vector3("position_m", box.centreM);
        const Eigen::Vector3d size = c.vector3("size_m", 2.0 * box.halfExtentM);
        if (!(size.minCoeff() > 0)) c.fail(c.keyPath("size_m"), "must be positive");
        box.halfExtentM = 0.5 * size;
        const Eigen::Vector3d rotation = c.vector3("rotation_deg", Eigen::Vector3d::Zero());
        box.orientation = rotationFromDegrees(rotation);
        box.restitution = c.number("restitution", box.restitution, 0, 1);
        box.friction = c.number("friction", box.friction, 0, 100);
        scene.world.colliders.push_back(box);
        scene.colliderRotationsDeg.push_back(rotation);
    });
    r.object("materials", [&](ObjectReader& mats) {
        // Keys are material names; "base" picks a preset to start from.
        for (auto it = root["materials"].begin(); it != root["materials"].end(); ++it) {
            const std::string name = it.key();
            mats.object(name, [&](ObjectReader& m) {
                const std::string baseName = m.string("base", "brick-masonry");
                const Material& base = m.checked("base", [&]() -> const Material& { return findMaterialPreset(baseName); });
                Material material = parseMaterial(m, name, base);
                bool replaced = false;
                for (Material& existing : scene.materials)
                    if (existing.name == name) existing = material, replaced = true;
                if (!replaced) scene.materials.push_back(material);
            });
        }
    });
    r.array("objects", [&](ObjectReader& o, size_t i) {
        ObjectSpec spec;
        spec.name = o.string("name", "object" + std::to_string(i));
        const bool hasMesh = o.has("mesh"), hasPrimitive = o.has("primitive");
        if (hasMesh == hasPrimitive) o.fail(o.keyPath("mesh"), "give exactly one of mesh or primitive");
        if (hasMesh) {
            std::filesystem::path mesh = o.string("mesh", "");
            if (mesh.is_relative()) mesh = std::filesystem::path(baseDirectory) / mesh;
            spec.meshPath = mesh.lexically_normal().string();
        }
        o.object("primitive", [&](ObjectReader& p) {
            Primitive prim;
            const std::string shape = p.string("shape", "box");
            if (shape == "box") {
                prim.shape = PrimitiveShape::Box;
                prim.sizeM = p.vector3("size_m", Eigen::Vector3d::Ones());
                if (!(prim.sizeM.minCoeff() > 0)) p.fail(p.keyPath("size_m"), "must be positive");
            } else if (shape == "sphere") {
                prim.shape = PrimitiveShape::Sphere;
                prim.sizeM = Eigen::Vector3d::Constant(p.number("radius_m", 0.5, 0, kHuge, true));
            } else if (shape == "cylinder") {
                prim.shape = PrimitiveShape::Cylinder;
                const double radius = p.number("radius_m", 0.5, 0, kHuge, true);
                prim.sizeM = Eigen::Vector3d(radius, radius, p.number("height_m", 1.0, 0, kHuge, true));
            } else {
                p.fail(p.keyPath("shape"), "'" + shape + "' is unknown (expected box, sphere or cylinder)");
            }
            spec.primitive = prim;
        });
        spec.positionM = o.vector3("position_m", spec.positionM);
        spec.rotationDeg = o.vector3("rotation_deg", spec.rotationDeg);
        spec.material = o.string("material", spec.material);
        o.checked("material", [&] { return scene.material(spec.material); });
        const std::string anchor = o.string("anchor", "none");
        if (anchor == "ground")
            spec.anchor = AnchorMode::Ground;
        else if (anchor != "none")
            o.fail(o.keyPath("anchor"), "'" + anchor + "' is unknown (expected none or ground)");
        scene.objects.push_back(spec);
    });
    r.array("charges", [&](ObjectReader& c, size_t) {
        Charge charge;
        charge.positionM = c.vector3("position_m", charge.positionM);
        charge.tntKg = c.number("tnt_kg", charge.tntKg, 0, 1e9, true);
        charge.detonationTimeS = c.number("detonation_time_s", charge.detonationTimeS, 0, 1e5);
        charge.burst = c.checked("burst", [&] { return parseEnum<decltype(charge.burst)>(c.string("burst", enumName(charge.burst))); });
        scene.charges.push_back(charge);
    });
    r.object("blast", [&](ObjectReader& b) {
        scene.blast.dataset = b.checked("dataset", [&] { return parseEnum<decltype(scene.blast.dataset)>(b.string("dataset", enumName(scene.blast.dataset))); });
        scene.blast.tableNodesPerDecade = static_cast<int>(b.integer("table_nodes_per_decade", scene.blast.tableNodesPerDecade, 2, 100000));
    });
    r.object("fracture", [&](ObjectReader& f) {
        FractureSettings& fs = scene.fracture;
        fs.algorithm = f.checked("algorithm", [&] { return parseEnum<decltype(fs.algorithm)>(f.string("algorithm", enumName(fs.algorithm))); });
        fs.weakening = f.boolean("weakening", fs.weakening);
        fs.orientation = f.boolean("orientation", fs.orientation);
        fs.minFragmentVoxels = f.integer("min_fragment_voxels", fs.minFragmentVoxels, 1, INT64_MAX);
        fs.smallFragments = f.checked("small_fragments", [&] { return parseEnum<SmallFragmentPolicy>(f.string("small_fragments", enumName(fs.smallFragments))); });
    });
    r.object("solver", [&](ObjectReader& s) {
        TimeStepSettings& ts = scene.timeStep;
        ts.integrator = s.checked("integrator", [&] { return parseEnum<decltype(ts.integrator)>(s.string("integrator", enumName(ts.integrator))); });
        ts.maxTimeStepS = s.number("max_time_step_s", ts.maxTimeStepS, 0, 10, true);
        ts.minTimeStepS = s.number("min_time_step_s", ts.minTimeStepS, 0, ts.maxTimeStepS, true);
        ts.frontFraction = s.number("front_fraction_voxels", ts.frontFraction, 0, 100, true);
        ts.pulseFraction = s.number("pulse_fraction", ts.pulseFraction, 0, 1, true);
        ts.speedFraction = s.number("speed_fraction_voxels", ts.speedFraction, 0, 100, true);
        scene.world.linearDragPerS = s.number("linear_drag_per_s", scene.world.linearDragPerS, 0, 1e6);
        scene.world.angularDragPerS = s.number("angular_drag_per_s", scene.world.angularDragPerS, 0, 1e6);
        scene.loads.reflectedPressure = s.boolean("reflected_pressure", scene.loads.reflectedPressure);
        scene.sleep.enabled = s.boolean("sleep", scene.sleep.enabled);
        scene.sleep.speedMS = s.number("sleep_speed_m_s", scene.sleep.speedMS, 0, 1e3);
        scene.sleep.timeS = s.number("sleep_time_s", scene.sleep.timeS, 0, 1e5);
    });
    r.object("collisions", [&](ObjectReader& c) {
        CollisionSettings& cs = scene.collisions;
        cs.method = c.checked("method", [&] { return parseEnum<decltype(cs.method)>(c.string("method", enumName(cs.method))); });
        cs.restitution = c.number("restitution", cs.restitution, 0, 1);
        cs.friction = c.number("friction", cs.friction, 0, 100);
        cs.solverIterations = static_cast<int>(c.integer("solver_iterations", cs.solverIterations, 1, 1000));
        cs.penetrationToleranceVoxels = c.number("penetration_tolerance_voxels", cs.penetrationToleranceVoxels, 0, 1, true);
    });
    r.object("output", [&](ObjectReader& o) {
        scene.output.vdb = o.boolean("vdb", scene.output.vdb);
        scene.output.densityGrid = o.boolean("density_grid", scene.output.densityGrid);
        scene.output.history = o.boolean("history", scene.output.history);
        scene.output.checkpointEveryS = o.number("checkpoint_every_s", scene.output.checkpointEveryS, 0, 1e9);
    });
    r.finish();
    scene.fracture.seed = scene.seed;
    if (scene.objects.empty()) r.fail("objects", "the scene has no objects");
    return scene;
}

Scene loadScene(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw InputError(path + ": cannot open scene file");
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::filesystem::path base = std::filesystem::absolute(path).parent_path();
    return parseScene(buffer.str(), path, base.string());
}

nlohmann::json sceneToJson(const Scene& scene)
{
    auto vec = [](const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); };
    json j;
    j["voxel_size_m"] = scene.voxelSizeM;
    j["duration_s"] = scene.durationS;
    j["frame_rate_hz"] = scene.frameRateHz;
    j["seed"] = scene.seed;
    j["max_voxels"] = scene.maxVoxels;
    j["gravity_m_s2"] = vec(scene.world.gravityMS2);
    j["atmosphere"] = {{"pressure_Pa", scene.blast.atmosphere.pressurePa}, {"temperature_K", scene.blast.atmosphere.temperatureK}};
    const GroundPlane& g = scene.world.ground;
    j["ground"] = {{"enabled", g.enabled}, {"normal", vec(g.normal)}, {"height_m", g.offsetM},
                   {"restitution", g.restitution}, {"friction", g.friction}};
    json colliders = json::array();
    for (size_t i = 0; i < scene.world.colliders.size(); ++i) {
        const StaticBox& b = scene.world.colliders[i];
        colliders.push_back({{"position_m", vec(b.centreM)}, {"size_m", vec(2.0 * b.halfExtentM)},
                             {"rotation_deg", vec(scene.colliderRotationsDeg[i])}, {"restitution", b.restitution}, {"friction", b.friction}});
    }
    j["colliders"] = colliders;
    json materials = json::object();
    for (const Material& m : scene.materials) {
        materials[m.name] = {{"density_kg_m3", m.densityKgM3},       {"mean_yield_Pa", m.meanYieldPa},
                             {"yield_variation", m.yieldVariation},  {"weakening_fraction", m.weakeningFraction},
                             {"orientation_factor", m.orientationFactor}, {"damage_rate_per_s", m.damageRatePerS},
                             {"damage_stress_scale_per_Pa", m.damageStressScalePerPa}};
    }
    j["materials"] = materials;
    json objects = json::array();
    for (const ObjectSpec& o : scene.objects) {
        json oj = {{"name", o.name}, {"position_m", vec(o.positionM)}, {"rotation_deg", vec(o.rotationDeg)},
                   {"material", o.material}, {"anchor", o.anchor == AnchorMode::Ground ? "ground" : "none"}};
        if (o.primitive) {
            const Primitive& p = *o.primitive;
            if (p.shape == PrimitiveShape::Box)
                oj["primitive"] = {{"shape", "box"}, {"size_m", vec(p.sizeM)}};
            else if (p.shape == PrimitiveShape::Sphere)
                oj["primitive"] = {{"shape", "sphere"}, {"radius_m", p.sizeM.x()}};
            else
                oj["primitive"] = {{"shape", "cylinder"}, {"radius_m", p.sizeM.x()}, {"height_m", p.sizeM.z()}};
        } else {
            oj["mesh"] = o.meshPath;
        }
        objects.push_back(oj);
    }
    j["objects"] = objects;
    json charges = json::array();
    for (const Charge& c : scene.charges)
        charges.push_back({{"position_m", vec(c.positionM)}, {"tnt_kg", c.tntKg}, {"detonation_time_s", c.detonationTimeS},
                           {"burst", enumName(c.burst)}});
    j["charges"] = charges;
    j["blast"] = {{"dataset", enumName(scene.blast.dataset)}, {"table_nodes_per_decade", scene.blast.tableNodesPerDecade}};
    const FractureSettings& f = scene.fracture;
    j["fracture"] = {{"algorithm", enumName(f.algorithm)}, {"weakening", f.weakening}, {"orientation", f.orientation},
                     {"min_fragment_voxels", f.minFragmentVoxels},
                     {"small_fragments", enumName(f.smallFragments)}};
    const TimeStepSettings& t = scene.timeStep;
    j["solver"] = {{"integrator", enumName(t.integrator)},
                   {"max_time_step_s", t.maxTimeStepS},
                   {"min_time_step_s", t.minTimeStepS},
                   {"front_fraction_voxels", t.frontFraction},
                   {"pulse_fraction", t.pulseFraction},
                   {"speed_fraction_voxels", t.speedFraction},
                   {"linear_drag_per_s", scene.world.linearDragPerS},
                   {"angular_drag_per_s", scene.world.angularDragPerS},
                   {"reflected_pressure", scene.loads.reflectedPressure},
                   {"sleep", scene.sleep.enabled},
                   {"sleep_speed_m_s", scene.sleep.speedMS},
                   {"sleep_time_s", scene.sleep.timeS}};
    const CollisionSettings& cs = scene.collisions;
    j["collisions"] = {{"method", enumName(cs.method)},
                       {"restitution", cs.restitution},
                       {"friction", cs.friction},
                       {"solver_iterations", cs.solverIterations},
                       {"penetration_tolerance_voxels", cs.penetrationToleranceVoxels}};
    j["output"] = {{"vdb", scene.output.vdb}, {"density_grid", scene.output.densityGrid}, {"history", scene.output.history},
                   {"checkpoint_every_s", scene.output.checkpointEveryS}};
    return j;
}

}  // namespace spall
