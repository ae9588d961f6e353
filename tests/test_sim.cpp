#include "TestUtil.h"

#include <spall/io/Scene.h>
#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

using namespace spall;

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

const char* kSmallScene = R"({
  "voxel_size_m": 0.1, "duration_s": 0.5, "frame_rate_hz": 24, "seed": 3,
  "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [2.0, 0.3, 1.5]},
               "position_m": [0, 0, 0.75], "material": "brick-masonry", "anchor": "ground"}],
  "charges": [{"position_m": [0.2, -2.0, 0.0], "tnt_kg": 3.0, "burst": "surface"}],
  "colliders": [{"position_m": [0, 3, 0.5], "size_m": [4, 0.5, 1], "rotation_deg": [0, 0, 10]}]
})";

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
    EXPECT_NE(errorOf(R"({"objects": [{"mesh": "missing.obj"}]})").find("missing.obj"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [0, 0, 0], "tnt_kg": 1}]})").find("inside object"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"tnt_kg": -2}]})").find("charges[0].tnt_kg"), std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "charges": [{"position_m": [5,0,0], "burst": "air"}]})").find("charges[0].burst"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "colliders": [{"size_m": [1, 0, 1]}]})").find("colliders[0].size_m: must be positive"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "colliders": [{"colour": 1}]})").find("colliders[0].colour: unknown key"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "solver": {"integrator": "leapfrog"}})").find("solver.integrator"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "fracture": {"small_fragments": "burn"}})").find("fracture.small_fragments"),
              std::string::npos);
    EXPECT_NE(errorOf(R"({"objects": [{)" + box + R"(}], "collisions": {"method": "sweep"}})").find("collisions.method"),
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
    for (const char* name : {"two-charges-concrete.json", "pillar-davison-stevens.json"}) EXPECT_NO_THROW(loadScene(dir + name)) << name;
}

TEST(Scene, ResolvedSceneParsesBackToItself)
{
    const Scene a = parseScene(kSmallScene, "small", ".");
    const nlohmann::json j = sceneToJson(a);
    const Scene b = parseScene(j.dump(), "resolved", ".");
    EXPECT_EQ(sceneToJson(b), j);
}

TEST(Simulation, ConservesVoxelsAndGivesTheSameResultForAnyThreadCount)
{
    const Scene scene = parseScene(kSmallScene, "small", ".");
    std::vector<std::vector<double>> states;
    for (int threads : {1, 2}) {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
        Simulation sim(scene);
        const int64_t voxels = sim.initialVoxelCount();
        sim.advanceTo(0.25);
        int64_t total = 0;
        std::vector<double> state;
        for (const Body& b : sim.bodies()) {
            total += b.mass.voxelCount;
            ASSERT_TRUE(b.positionM.allFinite() && b.linearVelocityMS.allFinite());
            ASSERT_NEAR(b.orientation.norm(), 1.0, 1e-12);
            for (int k = 0; k < 3; ++k) {
                state.push_back(b.positionM[k]);
                state.push_back(b.linearVelocityMS[k]);
            }
            state.push_back(double(b.id));
            if (!b.anchored) {
                EXPECT_GT(b.positionM.z(), 0.0);
            }
        }
        EXPECT_EQ(total, voxels);
        EXPECT_GT(sim.bodies().size(), 1u) << "the charge must break the wall";
        states.push_back(state);
    }
    EXPECT_EQ(states[0], states[1]) << "bit-identical with 1 and 2 threads";
}

TEST(Simulation, TimeStepIsFineWhileTheFrontCrossesAndCoarseLater)
{
    const Scene scene = parseScene(kSmallScene, "small", ".");
    Simulation sim(scene);
    const double arrival = sim.field().tableParameters(0, 1.9).arrivalTimeS;
    sim.advanceTo(arrival + 1e-5);
    const double during = sim.chooseTimeStep(sim.field().openWindows(sim.timeS()));
    EXPECT_LE(during * sim.field().shockSpeedMS(0, 2.0), 0.5 * scene.voxelSizeM * 1.0001);
    sim.advanceTo(0.4);
    EXPECT_GT(sim.chooseTimeStep(sim.field().openWindows(sim.timeS())), 50 * during);
}
