#include <spall/scene/Scene.h>

#include "FieldIo.h"

#include <spall/core/Error.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace spall {

using nlohmann::json;

template <>
const std::vector<Field<ObjectSpec>>& fieldTable<ObjectSpec>()
{
    // mesh and primitive are read by hand: exactly one of them, and a primitive's keys depend on
    // its shape.
    static const std::vector<Field<ObjectSpec>> table = {
        {"name", &ObjectSpec::name},
        {"position_m", &ObjectSpec::positionM},
        {"rotation_deg", &ObjectSpec::rotationDeg},
        {"linear_velocity_m_s", &ObjectSpec::linearVelocityMS},
        {"angular_velocity_rad_s", &ObjectSpec::angularVelocityRadS},
        {"material", &ObjectSpec::material},
        {"anchor", choice(&ObjectSpec::anchor)},
        {"inside", choice(&ObjectSpec::inside)},
        {"shell_thickness_m", &ObjectSpec::shellThicknessM, closed(0, 1e3)},
        {"mesh_unit", choice(&ObjectSpec::meshUnit)},
        {"scale", &ObjectSpec::scale, closed(1e-6, 1e6)},
    };
    return table;
}

double objectUnitM(const ObjectSpec& spec)
{
    // Exact by definition: 1 in = 25.4 mm, 1 ft = 12 in (international yard and pound, 1959).
    static constexpr double kMetresPer[] = {1.0, 0.01, 0.001, 0.0254, 0.3048};
    return kMetresPer[int(spec.meshUnit)] * spec.scale;
}

template <>
const std::vector<Field<OutputSettings>>& fieldTable<OutputSettings>()
{
    static const std::vector<Field<OutputSettings>> table = {
        {"output.vdb", &OutputSettings::vdb},
        {"output.fragment_grids", choice(&OutputSettings::fragmentGrids)},
        {"output.level_set_subdivisions", &OutputSettings::levelSetSubdivisions, closed(2, 8)},
        {"output.fracture_smoothing_steps", &OutputSettings::fractureSmoothingSteps, closed(0, 100)},
        {"output.fracture_roughness_voxels", &OutputSettings::fractureRoughnessVoxels, closed(0.0, 0.2)},
        {"output.gltf_max_triangles_per_piece", &OutputSettings::gltfMaxTrianglesPerPiece, closed(0, 1e9)},
        {"output.density_grid", &OutputSettings::densityGrid},
        {"output.debris_level_set", &OutputSettings::debrisLevelSet},
        {"output.first_frame", &OutputSettings::firstFrame, closed(0, 999000)},
        {"output.velocity_grid", &OutputSettings::velocityGrid},
        {"output.history", &OutputSettings::history},
        {"output.checkpoint_every_s", &OutputSettings::checkpointEveryS, closed(0, 1e9)},
    };
    return table;
}

template <>
const std::vector<Field<Scene>>& fieldTable<Scene>()
{
    static const std::vector<Field<Scene>> table = {
        {"voxel_size_m", &Scene::voxelSizeM, aboveZeroUpTo(100)},
        {"duration_s", &Scene::durationS, closed(0, 1e5)},
        {"frame_rate_hz", &Scene::frameRateHz, aboveZeroUpTo(1e4)},
        {"seed", &Scene::seed, atLeast(0)},
        {"max_voxels", &Scene::maxVoxels, atLeast(1)},
    };
    return table;
}

namespace {

/// Calls f on each settings struct a scene holds once, in one order for reading and writing.
template <typename SceneT, typename F>
void forEachSettings(SceneT& scene, F&& f)
{
    f(scene);
    f(scene.world);
    f(scene.world.ground);
    f(scene.blast.atmosphere);
    f(scene.blast);
    f(scene.loads);
    f(scene.fracture);
    f(scene.lattice);
    f(scene.timeStep);
    f(scene.sleep);
    f(scene.collisions);
    f(scene.output);
}

constexpr double kHuge = 1e12;

/// Reads one field outside any table (the primitive's keys, which depend on its shape).
template <typename S>
void readOne(ObjectReader& r, const Field<S>& field, S& value)
{
    if (const json* v = r.raw(field.key)) readField(r, field.key, *v, field, value);
}

Primitive readPrimitive(ObjectReader& p)
{
    struct Round {
        double radiusM = 0.5, heightM = 1.0;
    };
    Primitive prim;
    prim.shape = p.checked("shape", [&] { return parseEnum<PrimitiveShape>(p.string("shape", "box")); });
    Round round;
    switch (prim.shape) {
    case PrimitiveShape::Box: readOne(p, Field<Primitive>{"size_m", &Primitive::sizeM, {}, 1.0, VectorCheck::Positive}, prim); break;
    case PrimitiveShape::Sphere:
        readOne(p, Field<Round>{"radius_m", &Round::radiusM, aboveZeroUpTo(kHuge)}, round);
        prim.sizeM = Eigen::Vector3d::Constant(round.radiusM);
        break;
    case PrimitiveShape::Cylinder:
        readOne(p, Field<Round>{"radius_m", &Round::radiusM, aboveZeroUpTo(kHuge)}, round);
        readOne(p, Field<Round>{"height_m", &Round::heightM, aboveZeroUpTo(kHuge)}, round);
        prim.sizeM = Eigen::Vector3d(round.radiusM, round.radiusM, round.heightM);
        break;
    }
    return prim;
}

json primitiveToJson(const Primitive& p)
{
    switch (p.shape) {
    case PrimitiveShape::Box: return {{"shape", "box"}, {"size_m", {p.sizeM.x(), p.sizeM.y(), p.sizeM.z()}}};
    case PrimitiveShape::Sphere: return {{"shape", "sphere"}, {"radius_m", p.sizeM.x()}};
    case PrimitiveShape::Cylinder: return {{"shape", "cylinder"}, {"radius_m", p.sizeM.x()}, {"height_m", p.sizeM.z()}};
    }
    return {};
}

ObjectSpec readObject(ObjectReader& o, size_t index, const Scene& scene, const std::string& baseDirectory)
{
    ObjectSpec spec;
    spec.name = "object" + std::to_string(index);
    readFields(o, spec);
    o.checked("material", [&] { return scene.material(spec.material); });
    const bool hasMesh = o.has("mesh"), hasPrimitive = o.has("primitive");
    if (hasMesh == hasPrimitive) o.fail(o.keyPath("mesh"), "give exactly one of mesh or primitive");
    if (hasMesh) {
        std::filesystem::path mesh = o.string("mesh", "");
        if (mesh.is_relative()) mesh = std::filesystem::path(baseDirectory) / mesh;
        // Absolute, so the resolved scene (scene.json, a checkpoint's copy) reads back from anywhere.
        spec.meshPath = std::filesystem::absolute(mesh).lexically_normal().string();
    } else {
        spec.primitive = readPrimitive(*o.child("primitive"));
        if (spec.inside != InsideTest::Auto) o.fail(o.keyPath("inside"), "applies to meshes only; a primitive's inside is exact");
        if (spec.shellThicknessM > 0) o.fail(o.keyPath("shell_thickness_m"), "applies to meshes only");
        if (spec.meshUnit != MeshUnit::Metre) o.fail(o.keyPath("mesh_unit"), "applies to meshes only; a primitive's sizes are in metres");
    }
    return spec;
}

/// Scene materials: keys are names, "base" picks the preset to start from.
void readMaterials(ObjectReader& r, const json& root, Scene& scene)
{
    ObjectReader* materials = r.child("materials");
    if (!materials) return;
    for (auto it = root["materials"].begin(); it != root["materials"].end(); ++it) {
        ObjectReader& m = *materials->child(it.key());
        const std::string baseName = m.string("base", "brick-masonry");
        Material material = m.checked("base", [&]() -> const Material& { return findMaterialPreset(baseName); });
        material.name = it.key();
        readFields(m, material);
        if (const FieldProblem problem = structureProblem(material); !problem.key.empty()) m.fail(m.keyPath(problem.key), problem.reason);
        material.source = "scene " + r.file();
        bool replaced = false;
        for (Material& existing : scene.materials)
            if (existing.name == material.name) existing = material, replaced = true;
        if (!replaced) scene.materials.push_back(material);
    }
}

/// A charge's burst follows from its height above the ground unless the scene names it: a
/// surface burst within surfaceBurstHeightM of the ground, free air above it. A named surface
/// burst well above the ground is an error: the hemispherical data would not apply.
void resolveBurst(ObjectReader& c, size_t index, const GroundPlane& ground, Charge& charge)
{
    const double heightM = ground.enabled ? ground.normal.normalized().dot(charge.positionM) - ground.offsetM : 1e300;
    const double surfaceM = surfaceBurstHeightM(charge.tntKg);
    if (!c.has("burst")) {
        charge.burst = heightM <= surfaceM ? BurstType::Surface : BurstType::FreeAir;
        return;
    }
    if (charge.burst == BurstType::Surface && ground.enabled && heightM > surfaceM) {
        std::ostringstream reason;
        reason << "'surface', but charge " << index << " is " << heightM << " m above the ground; a surface burst of " << charge.tntKg
               << " kg sits within " << surfaceM << " m of it (omit burst for free air)";
        c.fail(c.keyPath("burst"), reason.str());
    }
}

/// What follows from the values read, and what no single field can check.
void completeScene(ObjectReader& r, Scene& scene)
{
    scene.world.ground.normal.normalize();
    for (StaticBox& box : scene.world.colliders) box.orientation = rotationFromDegrees(box.rotationDeg);
    if (scene.timeStep.minTimeStepS > scene.timeStep.maxTimeStepS)
        r.fail("solver.min_time_step_s", "must not exceed solver.max_time_step_s");
    if (scene.objects.empty()) r.fail("objects", "the scene has no objects");
    if (scene.output.debrisLevelSet && scene.output.fragmentGrids != FragmentGrids::LevelSet)
        r.fail("output.debris_level_set", "needs output.fragment_grids \"level_set\": it is the union of the pieces' level sets");
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
  "voxel_size_m": 0.025,
  "duration_s": 2.0,
  "frame_rate_hz": 24,
  "seed": 7,
  "objects": [
    {
      "name": "wall",
      "primitive": {"shape": "box", "size_m": [1.125, 0.225, 0.9]},
      "position_m": [0.0, 0.0, 0.45],
      "material": "brick-masonry",
      "anchor": "ground"
    }
  ],
  "charges": [
    {"position_m": [0.0, -0.4, 0.6], "tnt_kg": 0.4, "detonation_time_s": 0.0, "burst": "free-air"}
  ],
  "fracture": {"algorithm": "lattice"},
  "lattice": {"max_vibration_s": 0.03, "handoff_energy_fraction": 0.2}
}
)";
}

const char* paperWallSceneJson()
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
  ],
  "fracture": {"algorithm": "yield-limit"}
}
)";
}

Scene parseScene(const std::string& text, const std::string& sourceName, const std::string& baseDirectory)
{
    const json root = parseJsonStrictly(text, sourceName);
    Scene scene;
    scene.sourceName = sourceName;
    scene.materials = materialPresets();
    ObjectReader r(root, sourceName, "");
    forEachSettings(scene, [&](auto& settings) { readFields(r, settings); });
    r.array("colliders", [&](ObjectReader& c, size_t) {
        StaticBox box;
        readFields(c, box);
        scene.world.colliders.push_back(box);
    });
    readMaterials(r, root, scene);
    r.array("objects", [&](ObjectReader& o, size_t i) { scene.objects.push_back(readObject(o, i, scene, baseDirectory)); });
    r.array("charges", [&](ObjectReader& c, size_t i) {
        Charge charge;
        readFields(c, charge);
        scene.charges.push_back(charge);
        resolveBurst(c, i, scene.world.ground, scene.charges.back());
    });
    r.finish();
    completeScene(r, scene);
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

json sceneToJson(const Scene& scene)
{
    json j;
    forEachSettings(scene, [&](const auto& settings) { writeFields(settings, j); });
    j["colliders"] = json::array();
    for (const StaticBox& box : scene.world.colliders) writeFields(box, j["colliders"].emplace_back());
    j["materials"] = json::object();
    for (const Material& m : scene.materials) writeFields(m, j["materials"][m.name]);
    j["objects"] = json::array();
    for (const ObjectSpec& o : scene.objects) {
        json& oj = j["objects"].emplace_back();
        writeFields(o, oj);
        if (o.primitive)
            oj["primitive"] = primitiveToJson(*o.primitive);
        else
            oj["mesh"] = o.meshPath;
    }
    j["charges"] = json::array();
    for (const Charge& c : scene.charges) writeFields(c, j["charges"].emplace_back());
    return j;
}

}  // namespace spall
