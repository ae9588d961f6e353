// Scenes as a user writes them: every error names its key and reason, the shipped scenes parse,
// a resolved scene holds every key, and what set-up derives from a scene (burst type, supports,
// voxel and memory budgets).
#include "TestUtil.h"

#include <spall/scene/Scene.h>
#include <spall/sim/Checkpoint.h>
#include <spall/sim/MemoryBudget.h>
#include <spall/run/Run.h>
#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

using namespace spall;
using test::kSmallScene;

namespace {

std::string errorOf(const std::string& json)
{
    try {
        const Scene s = parseScene(json, "scene.json", ".");
        Simulation sim(s);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Scene, ErrorsNameTheKeyAndReason)
{
    EXPECT_NE(errorOf("{").find("not valid JSON"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [], "colour": 1})").find("colour: unknown key"), std::string::npos);
    EXPECT_NE(errorOf(R"({"voxel_size_m": "big"})").find("voxel_size_m: must be a number"), std::string::npos);
    EXPECT_NE(errorOf(R"({"voxel_size_m": -1})").find("voxel_size_m: must be in"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": []})").find("no objects"), std::string::npos);
    const std::string box = R"("primitive": {"shape": "box", "size_m": [1, 1, 1]})";
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(, "material": "cheese"}]})").find("objects[0].material"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(, "spin": 1}]})").find("objects[0].spin: unknown key"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(, "linear_velocity_m_s": [0, 1]}]})").find("objects[0].linear_velocity_m_s: must be an array of 3"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(, "anchor": "ground", "angular_velocity_rad_s": [0, 0, 1]}]})")
                  .find("objects[0]: 'object0' is anchored and cannot start moving"),
              std::string::npos);
    // A key twice: JSON leaves it undefined and the parser kept the last (issue 50).
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}, {)" + box + R"(, "material": "glass", "material": "wood"}]})")
                  .find("objects[1].material: the key appears twice"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"seed": 1, "objects": [], "seed": 2})").find("seed: the key appears twice"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{"mesh": "missing.obj"}]})").find("missing.obj"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(, "shell_thickness_m": 0.2}]})").find("objects[0].shell_thickness_m: applies to meshes only"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(, "inside": "level-set"}]})").find("objects[0].inside: applies to meshes only"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [0, 0, 0], "tnt_kg": 1}]})").find("inside object"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"tnt_kg": -2}]})").find("charges[0].tnt_kg"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [5,0,0], "burst": "air"}]})").find("charges[0].burst"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "colliders": [{"size_m": [1, 0, 1]}]})").find("colliders[0].size_m: must be positive"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "colliders": [{"colour": 1}]})").find("colliders[0].colour: unknown key"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "colliders": [{"holds": "glued"}]})").find("colliders[0].holds"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"checkpoint_every_frames": 1}})")
                  .find("output.checkpoint_every_frames: unknown key, replaced by output.checkpoint_every_s"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"checkpoint_every_s": -1}})").find("output.checkpoint_every_s"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"fragment_grids": "mesh"}})").find("output.fragment_grids"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"level_set_subdivisions": 1}})").find("output.level_set_subdivisions"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"fracture_smoothing_steps": -1}})").find("output.fracture_smoothing_steps"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"level_set_smoothing_steps": 4}})")
                  .find("output.level_set_smoothing_steps: unknown key, replaced by output.fracture_smoothing_steps"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"fracture_roughness_voxels": 0.3}})").find("output.fracture_roughness_voxels"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"fragment_grids": "fog", "debris_level_set": true}})")
                  .find("output.debris_level_set: needs output.fragment_grids \"level_set\""),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "output": {"first_frame": -1}})").find("output.first_frame"), std::string::npos);
    {
        // 32 free-air charges above the ground are 64 with their images: more than weakening can tell apart.
        std::string charges;
        for (int i = 0; i < 32; ++i) charges += std::string(i ? "," : "") + R"({"position_m": [)" + std::to_string(3 + i) + R"(, 0, 2], "burst": "free-air"})";
        EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "fracture": {"algorithm": "yield-limit"}, "charges": [)" + charges + "]}").find("charges: 64 charges (ground images included)"),
                  std::string::npos);
    }
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "solver": {"integrator": "leapfrog"}})").find("solver.integrator"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "fracture": {"small_fragments": "burn"}})").find("fracture.small_fragments"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "collisions": {"method": "sweep"}})").find("collisions.method"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "seed": -1})").find("seed: must be an integer that fits in 64 bits, not negative"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "collisions": {"solver_iterations": 4294967297}})")
                  .find("collisions.solver_iterations: must be an integer that fits in 32 bits"),
              std::string::npos);
}

TEST(Scene, ABuriedChargeIsRefusedNamingItsPlace)
{
    // The blast model is of charges in air or on the surface: one under the ground or inside a
    // collider would run as a surface or free-air burst, silently.
    const std::string box = R"("primitive": {"shape": "box", "size_m": [1, 1, 1]})";
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [5, 0, -1]}]})").find("charges[0].position_m: the charge is 1"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [5, 0, 0.5]}], "colliders": [{"position_m": [5, 0, 0.5]}]})")
                  .find("charges[0].position_m: the charge is inside colliders[0]"),
              std::string::npos);
    EXPECT_EQ(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [5, 0, 0], "burst": "surface"}]})"), "");
}

TEST(Scene, MaterialAndLatticeErrorsNameTheKeyAndReason)
{
    const std::string box = R"("primitive": {"shape": "box", "size_m": [1, 1, 1]})";
    // Fracture from stress: its settings and the material values it reads.
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"bulk_viscosity": -0.1}})").find("lattice.bulk_viscosity: must be in"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"handoff_energy_fraction": 2}})").find("lattice.handoff_energy_fraction"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"max_vibration_s": "long"}})").find("lattice.max_vibration_s: must be a number"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"handoff_residual_strength": 1.5}})").find("lattice.handoff_residual_strength: must be in"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"damage_law": "paper"}})").find("lattice.damage_law"), std::string::npos);
    for (const char* flag : {"impact_fracture", "separate_during_blast"})
        EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {")" + flag + R"(": "yes"}})").find(std::string("lattice.") + flag),
                  std::string::npos)
            << flag;
    for (const char* interval : {"0", "-0.001", "2"})
        EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"handoff_check_interval_s": )" + interval + "}}")
                      .find("lattice.handoff_check_interval_s: must be in"),
                  std::string::npos)
            << interval;
    for (const char* blocks : {"0", "9", "2.5"})
        EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "lattice": {"particle_voxels": )" + blocks + "}}").find("lattice.particle_voxels: must be"),
                  std::string::npos)
            << blocks;
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "solver": {"air_drag": "stokes"}})").find("solver.air_drag"), std::string::npos);
    for (const std::string bad : {R"("youngs_modulus_pa": -1)", R"("poissons_ratio": 0.5)", R"("density_kg_m3": 0)"}) {
        const std::string key = bad.substr(1, bad.find('"', 1) - 1);
        EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "ground": {)" + bad + "}}").find("ground." + key + ": must be"), std::string::npos) << bad;
    }
    const std::string stone = R"(}], "materials": {"stone": {)";
    for (const std::string bad : {R"("youngs_modulus_Pa": 0)", R"("poisson_ratio": 0.5)", R"("tensile_strength_Pa": -1)",
                                  R"("fracture_energy_J_per_m2": 0)", R"("shear_strength_Pa": 0)", R"("friction_coefficient": -0.2)",
                                  R"("unit_length_m": -0.2)", R"("joint_thickness_m": 2)", R"("unit_tensile_strength_Pa": -1)",
                                  R"("unit_friction_coefficient": 20)", R"("strength_cov": 1.5)", R"("strength_correlation_length_m": 0)",
                                  R"("damping_ratio": -0.1)", R"("damping_ratio": 0.5)", R"("compressive_strength_Pa": -1)",
                                  R"("compressive_fracture_energy_J_per_m2": -5)", R"("unit_strength_cov": 2)", R"("strength_weibull_modulus": -1)",
                                  R"("strength_reference_area_m2": 0)"}) {
        const std::string key = bad.substr(1, bad.find('"', 1) - 1);
        EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + bad + "}}}").find("materials.stone." + key + ": must be"), std::string::npos) << bad;
    }
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("strength_rate_law": "fast"}}})").find("materials.stone.strength_rate_law"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("unit_length_axis": "z"}}})").find("materials.stone.unit_length_axis"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("strength_distribution": "gumbel"}}})").find("materials.stone.strength_distribution"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("strength_distribution": "weibull"}}})")
                  .find("materials.stone.strength_weibull_modulus: must be above 0 when strength_distribution is weibull"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("unit_bond_pattern": "herringbone"}}})").find("materials.stone.unit_bond_pattern"),
              std::string::npos);
    // Brick masonry (the default base) is built of units: a unit without a height is an error,
    // and a unit length of 0 makes the material homogeneous.
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("unit_height_m": 0}}})").find("materials.stone.unit_height_m: must be above 0 when"),
              std::string::npos);
    EXPECT_EQ(errorOf(R"({"objects": [{)" + box + stone + R"("unit_length_m": 0, "unit_height_m": 0}}})"), "");
    // A grain needs its values along it, and a material has units or a grain, not both.
    const std::string pine = R"(}], "materials": {"pine": {"base": "wood", )";
    EXPECT_EQ(errorOf(R"({"objects": [{)" + box + pine + R"("grain_axis": "x"}}})"), "");
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + pine + R"("grain_axis": "w"}}})").find("materials.pine.grain_axis"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + pine + R"("along_grain_tensile_strength_Pa": 0}}})")
                  .find("materials.pine.along_grain_tensile_strength_Pa: must be above 0 when grain_axis is set"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("grain_axis": "z"}}})").find("materials.stone.grain_axis: must be none for a material built of units"),
              std::string::npos);
    // A material that crushes needs the energy crushing takes, and with a grain both along it.
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + stone + R"("compressive_strength_Pa": 5e6}}})")
                  .find("materials.stone.compressive_fracture_energy_J_per_m2: must be above 0 when compressive_strength_Pa is"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + pine + R"("along_grain_compressive_fracture_energy_J_per_m2": 0}}})")
                  .find("materials.pine.along_grain_compressive_fracture_energy_J_per_m2: must be above 0 when compressive_strength_Pa is"),
              std::string::npos);
    EXPECT_EQ(errorOf(R"({"objects": [{)" + box + pine + R"("compressive_strength_Pa": 0, "along_grain_compressive_strength_Pa": 0}}})"), "");
    // ... and values along it that a lattice can be calibrated to, against those across it
    // (refused where the scene is read, not when a body enters the deformable phase).
    EXPECT_EQ(errorOf(R"({"objects": [{)" + box + pine + R"("along_grain_shear_modulus_Pa": 1e6}}})"), "");
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + pine + R"("along_grain_youngs_modulus_Pa": 1e6}}})")
                  .find("materials.pine.along_grain_youngs_modulus_Pa: must be at least 4 nu E"),
              std::string::npos);
    EXPECT_EQ(errorOf(defaultSceneJson()), "");
}

TEST(Scene, NumberBeyondADoubleIsAnInputError)
{
    // Found by fuzz/fuzz_scene: nlohmann::json throws out_of_range, not parse_error, here.
    EXPECT_NE(errorOf(R"({"voxel_size_m": 1E400})").find("not valid JSON"), std::string::npos);
    EXPECT_NE(errorOf(R"({"x": 111111111111111111E1111111111111111})").find("not valid JSON"), std::string::npos);
}

TEST(Scene, ShippedScenesParseAndTheDefaultMatchesItsAsset)
{
    const std::string dir = SPALL_SOURCE_DIR "/assets/scenes/";
    const Scene asset = loadScene(dir + "default.json");
    const Scene builtIn = parseScene(defaultSceneJson(), "built-in", ".");
    EXPECT_EQ(sceneToJson(asset), sceneToJson(builtIn));
    EXPECT_EQ(sceneToJson(loadScene(dir + "brick-wall-yield-limit.json")), sceneToJson(parseScene(paperWallSceneJson(), "built-in", ".")));
    for (const char* name : {"two-charges-concrete.json", "pillar-davison-stevens.json", "brick-wall-lattice.json", "timber-post.json",
                             "concrete-slab-spall.json", "house-wall.json", "glass-pane.json", "block-at-pane.json"})
        EXPECT_NO_THROW(loadScene(dir + name)) << name;
}

namespace {

/// Every key a scene can hold, each with a value other than its default (written out by hand,
/// so it does not depend on the field tables it checks).
const char* kEveryKeyScene = R"({
  "voxel_size_m": 0.07, "duration_s": 1.5, "frame_rate_hz": 30, "seed": 42, "max_voxels": 123456,
  "gravity_m_s2": [0.1, 0.2, -9.7],
  "atmosphere": {"pressure_Pa": 90000, "temperature_K": 300},
  "ground": {"enabled": false, "normal": [0, 0.6, 0.8], "height_m": 0.5, "restitution": 0.3, "friction": 0.7, "youngs_modulus_pa": 8e7,
             "poissons_ratio": 0.35, "density_kg_m3": 1700},
  "colliders": [{"position_m": [1, 2, 3], "size_m": [1, 2, 0.5], "rotation_deg": [0, 0, 10], "restitution": 0.1, "friction": 0.2, "holds": "pinned", "bearing_pressure_pa": 20000}],
  "materials": {"stone": {"density_kg_m3": 2500, "mean_yield_Pa": 60000, "yield_variation": 0.2, "weakening_fraction": 0.3,
                          "orientation_factor": 0.05, "damage_rate_per_s": 200, "damage_stress_scale_per_Pa": 1e-5,
                          "youngs_modulus_Pa": 2e10, "poisson_ratio": 0.25, "tensile_strength_Pa": 4e6, "fracture_energy_J_per_m2": 90,
                          "shear_strength_Pa": 5e6, "friction_coefficient": 0.6, "strength_rate_law": "fib-mc2010",
                          "strength_cov": 0.15, "strength_correlation_length_m": 0.03, "unit_strength_cov": 0.2, "damping_ratio": 0.04,
                          "unit_length_m": 0.3, "unit_width_m": 0.1, "unit_height_m": 0.1, "joint_thickness_m": 0.012,
                          "unit_length_axis": "y", "unit_bond_pattern": "flemish", "unit_tensile_strength_Pa": 3e6, "unit_fracture_energy_J_per_m2": 60,
                          "unit_shear_strength_Pa": 2.5e6, "unit_friction_coefficient": 0.45,
                          "compressive_strength_Pa": 3e7, "compressive_fracture_energy_J_per_m2": 20000,
                          "colour_rgb": [0.3, 0.3, 0.25], "interior_colour_rgb": [0.4, 0.35, 0.3], "joint_colour_rgb": [0.5, 0.5, 0.45],
                          "roughness": 0.8, "transmission": 0.25},
                "oak": {"unit_length_m": 0, "youngs_modulus_Pa": 1e9, "strength_distribution": "weibull", "strength_weibull_modulus": 9,
                        "strength_reference_area_m2": 0.5, "grain_axis": "y", "along_grain_youngs_modulus_Pa": 12e9,
                        "along_grain_shear_modulus_Pa": 0.8e9, "along_grain_tensile_strength_Pa": 9e7,
                        "along_grain_fracture_energy_J_per_m2": 12000, "along_grain_shear_strength_Pa": 2e7,
                        "along_grain_compressive_strength_Pa": 4e7, "along_grain_compressive_fracture_energy_J_per_m2": 60000}},
  "objects": [{"name": "block", "primitive": {"shape": "box", "size_m": [1, 1, 1]}, "position_m": [0, 0, 0.5],
               "rotation_deg": [0, 0, 5], "material": "stone", "anchor": "ground", "scale": 1.5},
              {"name": "sheet", "mesh": "/meshes/sheet.obj", "position_m": [0, 0, 2], "rotation_deg": [0, 0, 0],
               "linear_velocity_m_s": [0, 10, 0], "angular_velocity_rad_s": [0, 0, 1],
               "material": "stone", "anchor": "none", "inside": "winding-number", "shell_thickness_m": 0.2, "mesh_unit": "in"}],
  "charges": [{"position_m": [0, -3, 0], "tnt_kg": 2, "detonation_time_s": 0.01, "burst": "free-air"}],
  "blast": {"dataset": "kinney-graham", "table_nodes_per_decade": 64},
  "fracture": {"algorithm": "davison-stevens", "weakening": false, "orientation": false, "min_fragment_voxels": 3,
               "small_fragments": "dust"},
  "lattice": {"bulk_viscosity": 0.2, "handoff_energy_fraction": 0.05, "max_vibration_s": 0.01, "handoff_check_interval_s": 0.002, "handoff_residual_strength": 0.2, "damage_law": "davison-stevens", "impact_fracture": true, "separate_during_blast": true, "particle_voxels": 2},
  "solver": {"integrator": "rk4", "max_time_step_s": 0.002, "min_time_step_s": 1e-6, "front_fraction_voxels": 0.4,
             "pulse_fraction": 0.05, "speed_fraction_voxels": 0.4, "air_drag": "none", "linear_drag_per_s": 0.1, "angular_drag_per_s": 0.2,
             "sleep": false, "sleep_speed_m_s": 0.1, "sleep_time_s": 1.0},
  "loads": {"model": "paper"},
  "collisions": {"method": "buckets", "restitution": 0.3, "friction": 0.5, "solver_iterations": 20,
                 "penetration_tolerance_voxels": 0.5},
  "output": {"vdb": false, "fragment_grids": "fog", "level_set_subdivisions": 4, "fracture_smoothing_steps": 2,
             "fracture_roughness_voxels": 0.1, "gltf_max_triangles_per_piece": 500, "density_grid": false, "debris_level_set": false,
             "first_frame": 1001, "velocity_grid": true, "history": false, "checkpoint_every_s": 10}
})";

/// Key paths of every leaf value, with list indices and material names as "*".
void leafPaths(const nlohmann::json& j, const std::string& path, std::map<std::string, nlohmann::json>& out, bool generic)
{
    if (j.is_object()) {
        for (auto it = j.begin(); it != j.end(); ++it) {
            const bool name = generic && path == "/materials";
            leafPaths(it.value(), path + "/" + (name ? "*" : it.key()), out, generic);
        }
    } else if (j.is_array() && !j.empty() && j[0].is_object()) {
        for (size_t i = 0; i < j.size(); ++i) leafPaths(j[i], path + "/" + (generic ? "*" : std::to_string(i)), out, generic);
    } else {
        out[path] = j;
    }
}

}  // namespace

TEST(Scene, ResolvedSceneHoldsEveryKeyWithItsValue)
{
    // Every key given comes back with its value: a field the writer omits or the reader ignores
    // would come back with its default. ("base" only picks a preset and is not written.)
    const nlohmann::json given = nlohmann::json::parse(kEveryKeyScene);
    const nlohmann::json resolved = sceneToJson(parseScene(given.dump(), "every-key", "."));
    std::map<std::string, nlohmann::json> givenLeaves, resolvedLeaves;
    leafPaths(given, "", givenLeaves, false);
    leafPaths(resolved, "", resolvedLeaves, false);
    for (const auto& [path, value] : givenLeaves) {
        ASSERT_TRUE(resolvedLeaves.count(path)) << path << " is not written";
        if (path == "/ground/normal") continue;  // normalised on reading (it is already unit here)
        EXPECT_EQ(resolvedLeaves[path], value) << path;
    }
    // ... and the scene above lists every key the writer knows, so none goes untested.
    std::map<std::string, nlohmann::json> known, listed;
    leafPaths(sceneToJson(parseScene(kSmallScene, "small", ".")), "", known, true);
    leafPaths(given, "", listed, true);
    for (const auto& [path, value] : known) EXPECT_TRUE(listed.count(path)) << path << " is missing from kEveryKeyScene";
    // Reading the resolved scene gives it back unchanged.
    EXPECT_EQ(sceneToJson(parseScene(resolved.dump(), "resolved", ".")), resolved);
}

TEST(Scene, AMeshInOtherUnitsTakesItsUnitAndAnObjectItsScale)
{
    // A cube 100 units on a side, modelled in centimetres: in metres it would be 100 m, far past
    // max_voxels at 0.1 m, and the error says how large it is and which key fixes it. (Its faces
    // are off the voxel centres: issue 50's round coordinates are another matter.)
    const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "spall-mesh-unit";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "cube.obj") << "v 0.5 0.5 0.5\nv 100.5 0.5 0.5\nv 100.5 100.5 0.5\nv 0.5 100.5 0.5\nv 0.5 0.5 100.5\nv 100.5 0.5 100.5\n"
                                       "v 100.5 100.5 100.5\nv 0.5 100.5 100.5\n"
                                       "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    const auto sceneWith = [&](const std::string& objectKeys) {
        return parseScene(R"({"voxel_size_m": 0.1, "max_voxels": 100000, "objects": [{"name": "cube", "mesh": "cube.obj")" + objectKeys + "}]}", "cube.json",
                          dir.string());
    };
    try {
        Simulation tooLarge(sceneWith(""));
        ADD_FAILURE() << "a 100 m cube at 0.1 m voxels ran";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("objects[0] ('cube') spans 100 x 100 x 100 m (mesh_unit \"m\", scale 1)"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("takes mesh_unit (cm, mm, in, ft) or scale"), std::string::npos) << e.what();
    }
    const auto volumeM3 = [](const Simulation& sim) { return sim.bodies().front().mass.voxelCount * std::pow(sim.scene().voxelSizeM, 3); };
    const Simulation centimetres(sceneWith(R"(, "mesh_unit": "cm")"));
    EXPECT_NEAR(volumeM3(centimetres), 1.0, 1e-9);
    const Simulation halved(sceneWith(R"(, "mesh_unit": "cm", "scale": 0.5)"));
    EXPECT_NEAR(volumeM3(halved), 0.125, 1e-9);
    // A primitive's sizes are metres: its scale applies, a mesh unit does not.
    const Scene box = parseScene(R"({"voxel_size_m": 0.1, "objects": [{"primitive": {"shape": "box", "size_m": [1, 1, 1]}, "scale": 2}]})", "box", ".");
    EXPECT_NEAR(volumeM3(Simulation(box)), 8.0, 0.01);
    EXPECT_THROW(parseScene(R"({"objects": [{"primitive": {"shape": "box", "size_m": [1, 1, 1]}, "mesh_unit": "cm"}]})", "box", "."), InputError);
    // An object larger than 100 m or smaller than a centimetre is noted with its extent.
    const Scene tiny = parseScene(R"({"voxel_size_m": 0.001, "objects": [{"mesh": "cube.obj", "mesh_unit": "mm", "scale": 0.05}]})", "tiny", dir.string());
    const std::vector<std::string> notes = Simulation(tiny).notes();
    EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& n) { return n.find("spans 0.005 x 0.005 x 0.005 m") != std::string::npos; }));
}

TEST(Scene, BurstFollowsTheChargesHeightAboveTheGround)
{
    // Within two charge radii of the ground (0.29 m for 20 kg) a charge is a surface burst
    // unless the scene says otherwise; above it, free air; a named surface burst 2 m up is an error.
    auto charges = [](const std::string& charge) {
        return R"({"objects": [{"primitive": {"shape": "box", "size_m": [1, 1, 1]}, "position_m": [0, 0, 0.5]}], "charges": [)" + charge + "]}";
    };
    EXPECT_EQ(parseScene(charges(R"({"position_m": [0, -4, 0.1], "tnt_kg": 20})"), "s.json", ".").charges[0].burst, BurstType::Surface);
    EXPECT_EQ(parseScene(charges(R"({"position_m": [0, -4, 2.0], "tnt_kg": 20})"), "s.json", ".").charges[0].burst, BurstType::FreeAir);
    EXPECT_EQ(parseScene(charges(R"({"position_m": [0, -4, 0.1], "tnt_kg": 20, "burst": "free-air"})"), "s.json", ".").charges[0].burst,
              BurstType::FreeAir);
    EXPECT_NE(errorOf(charges(R"({"position_m": [0, -4, 2.0], "tnt_kg": 20, "burst": "surface"})")).find("charges[0].burst: 'surface', but charge 0 is 2 m above the ground"),
              std::string::npos);
    EXPECT_NEAR(surfaceBurstHeightM(20.0), 2 * std::cbrt(3 * 20.0 / (4 * M_PI * 1600)), 1e-12);
}

TEST(Scene, APaneAnchoredToItsSupportsIsHeldAlongTheEdgesThatTouchThem)
{
    // A 1 × 0.1 × 1 m pane 2 m above the ground between two colliders at its left and right
    // edges: with `supports` exactly the voxels whose faces touch a collider are anchored (two
    // columns of 10 × 1); nothing touches the ground. Moved away, it is an error naming the object.
    auto pane = [](double gapM) {
        return R"({"voxel_size_m": 0.1, "objects": [{"name": "pane", "primitive": {"shape": "box", "size_m": [1, 0.1, 1]},
                    "position_m": [0, 0, 2.5], "anchor": "supports"}],
                   "colliders": [{"position_m": [)" + std::to_string(-0.55 - gapM) + R"(, 0, 2.5], "size_m": [0.1, 0.3, 1.2]},
                                 {"position_m": [)" + std::to_string(0.55 + gapM) + R"(, 0, 2.5], "size_m": [0.1, 0.3, 1.2]}]})";
    };
    const Simulation sim(parseScene(pane(0.02), "pane.json", "."));
    const Body& body = sim.state().bodies.at(0);
    EXPECT_TRUE(body.anchored);
    int anchored = 0;
    for (auto it = body.grid->cbeginValueOn(); it; ++it) {
        if (!(*it & kAnchorBit)) continue;
        ++anchored;
        EXPECT_TRUE(it.getCoord().x() == body.indexBounds.min().x() || it.getCoord().x() == body.indexBounds.max().x()) << it.getCoord();
    }
    EXPECT_EQ(anchored, 20);
    EXPECT_NE(errorOf(pane(0.05)).find("objects[0].anchor: no voxel of 'pane' touches the ground or a collider"), std::string::npos);
}

// Issue 21: a scene too large for max_voxels or for the machine is refused before anything is
// allocated, naming the figure and what to change.
TEST(Scene, ObjectsBeyondTheVoxelBudgetOrTheMemoryAreRefusedBeforeVoxelising)
{
    auto scene = [](const std::string& extra) {
        return R"({"voxel_size_m": 0.01, )" + extra +
               R"("objects": [{"primitive": {"shape": "box", "size_m": [2, 2, 2]}, "position_m": [0, 0, 1]},
                             {"primitive": {"shape": "box", "size_m": [2, 2, 2]}, "position_m": [5, 0, 1]}],
               "charges": [{"position_m": [0, -4, 0.1], "tnt_kg": 1}]})";
    };
    // Each box alone (201^3 = 8.1 M voxels) is under the limit of 10 M; together they are not.
    const std::string overVoxels = errorOf(scene(R"("max_voxels": 10000000, )"));
    EXPECT_NE(overVoxels.find("max_voxels: the objects' bounding boxes hold up to 1.62e+07 voxels"), std::string::npos) << overVoxels;
    // 24 bytes a voxel: 10^12 voxels need 24 TB, which no machine that runs this test has.
    const double available = availableMemoryBytes();
    ASSERT_GT(available, 0) << "MemAvailable is readable on Linux";
    EXPECT_LT(available, 1e13);
    const std::string overMemory = errorOf(R"({"voxel_size_m": 0.01, "max_voxels": 9000000000000000,
        "objects": [{"primitive": {"shape": "box", "size_m": [100, 100, 100]}, "position_m": [0, 0, 50]}],
        "charges": [{"position_m": [0, -60, 0.1], "tnt_kg": 1}]})");
    EXPECT_NE(overMemory.find("voxel_size_m: up to 1e+12 voxels need about 2.4e+04 GB"), std::string::npos) << overMemory;
    EXPECT_GT(estimateMemory(1e6).allBrokenBytes, 100 * estimateMemory(1e6).intactBytes) << "fragments cost far more than whole bodies";
}

TEST(Scene, FractureSettingsSayWhatTheyCannotSee)
{
    // The paper's rules say that they ignore impulse and shielding; a brick wall in voxels taller
    // than a course says its bricks are not resolved and names the particle size that would be.
    const auto notesOf = [](const std::string& json) { return Simulation(parseScene(json, "notes", ".")).notes(); };
    const auto said = [](const std::vector<std::string>& notes, const std::string& text) {
        return std::any_of(notes.begin(), notes.end(), [&](const std::string& note) { return note.find(text) != std::string::npos; });
    };
    const std::string wall = R"("objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [1.0, 0.2, 0.6]},
                                "position_m": [0, 0, 0.3], "material": "brick-masonry"}])";
    EXPECT_TRUE(said(notesOf("{" + wall + R"(, "voxel_size_m": 0.1, "fracture": {"algorithm": "yield-limit"}})"), "whatever its impulse"));
    EXPECT_FALSE(said(notesOf("{" + wall + R"(, "voxel_size_m": 0.1, "fracture": {"algorithm": "lattice"}})"), "whatever its impulse"));
    const std::vector<std::string> coarse = notesOf("{" + wall + R"(, "voxel_size_m": 0.1, "fracture": {"algorithm": "lattice"}})");
    EXPECT_TRUE(said(coarse, "objects[0] ('wall', brick-masonry): its lattice's particles (0.1 m")) << (coarse.empty() ? "" : coarse.front());
    EXPECT_TRUE(said(coarse, "particles of at most 0.075 m resolve its units"));
    EXPECT_FALSE(said(notesOf(defaultSceneJson()), "taller than a course"));
    // The same wall is two particles thick at 0.1 m; a concrete block 0.5 m thick a few
    // centimetres from a gram of TNT would spall to under its particles' 0.1 m.
    EXPECT_TRUE(said(coarse, "objects[0] ('wall') is 2 particles across its thinnest side (0.2 m)"));
    EXPECT_TRUE(said(coarse, "of at most 0.05 m puts four particles across"));
    const std::string block = R"("objects": [{"name": "block", "primitive": {"shape": "box", "size_m": [1.0, 0.5, 0.6]},
                                 "position_m": [0, 0, 0.3], "material": "concrete"}], "voxel_size_m": 0.1)";
    const std::vector<std::string> spalled =
        notesOf("{" + block + R"(, "charges": [{"position_m": [0, -0.3, 0.3], "tnt_kg": 0.001, "burst": "free-air"}]})");
    EXPECT_TRUE(said(spalled, "objects[0] ('block'): the nearest charge's reflected pulse would spall its far face to about"));
    EXPECT_FALSE(said(notesOf("{" + block + R"(, "charges": [{"position_m": [0, -3, 0.3], "tnt_kg": 10, "burst": "free-air"}]})"), "spall"));
    for (const std::string& note : notesOf(defaultSceneJson())) EXPECT_EQ(note.find("particles across"), std::string::npos) << note;
    // A charge 2 cm from the wall's face (Z = 0.02 m/kg^(1/3) for 1 kg) is nearer than the blast
    // data reach (issue 50); the default scene's is not.
    const std::string near = R"(, "voxel_size_m": 0.1, "charges": [{"position_m": [0, -0.12, 0.3], "tnt_kg": 1.0, "burst": "free-air"}])";
    const std::vector<std::string> nearNotes = notesOf("{" + wall + near + "}");
    EXPECT_TRUE(said(nearNotes, "m from objects[0] ('wall'), scaled distance")) << (nearNotes.empty() ? "" : nearNotes.back());
    EXPECT_TRUE(said(nearNotes, "nearer than the blast data's fits reach"));
    EXPECT_FALSE(said(notesOf(defaultSceneJson()), "nearer than the blast data"));
    // Davison–Stevens is fitted to a material's strain-rate law: brick masonry has none, concrete has.
    const std::string rateDamage = R"(, "lattice": {"damage_law": "davison-stevens"}})";
    EXPECT_TRUE(said(notesOf("{" + wall + R"(, "voxel_size_m": 0.1)" + rateDamage), "objects[0] ('wall', brick-masonry): lattice.damage_law \"davison-stevens\" is fitted"));
    EXPECT_FALSE(said(notesOf("{" + block + rateDamage), "damage_law"));
    // Issue 50: a run whose deformable phase could take long says so first, with the keys that
    // change it. A concrete wall 1 × 0.2 × 1 m at 1 cm is 200 000 particles and about 70 000
    // steps of 1.4 µs in 0.1 s; the default scene is cheap.
    const std::string wide = R"("objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [1.0, 0.2, 1.0]},
                                "position_m": [0, 0, 0.5], "material": "concrete"}], "voxel_size_m": 0.01,
                                "charges": [{"position_m": [0, -2, 0.5], "tnt_kg": 1}])";
    const std::vector<std::string> costly = notesOf("{" + wide + "}");
    EXPECT_TRUE(said(costly, "the deformable phase may take up to")) << (costly.empty() ? "" : costly.back());
    EXPECT_TRUE(said(costly, "lattice.max_vibration_s (0.1 s)"));
    EXPECT_FALSE(said(notesOf(defaultSceneJson()), "the deformable phase may take"));
}
