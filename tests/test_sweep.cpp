#include <spall/core/Error.h>
#include <spall/sweep/Sweep.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace spall;

namespace {

std::string writeScene(const std::string& name)
{
    const std::string dir = testing::TempDir() + "/sweep_" + name;
    std::filesystem::remove_all(dir);  // a sweep resumes what it finds: start from nothing
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/scene.json") << R"({"voxel_size_m": 0.1, "duration_s": 0.5, "seed": 40,
      "objects": [{"name": "box", "primitive": {"shape": "box", "size_m": [0.3, 0.3, 0.3]}, "position_m": [0, 0, 0.15]}],
      "charges": [{"position_m": [0, -0.6, 0.15], "tnt_kg": 1.0}]})";
    return dir + "/scene.json";
}

}  // namespace

TEST(Sweep, VariantsAreEveryCombinationOfTheAxesTimesTheSeeds)
{
    const SweepPlan plan = planSweep(writeScene("product"),
                                     {parseSweepAxis("charges[0].tnt_kg=1,2.5"), parseSweepAxis("objects[0].material=concrete,wood,glass")}, 2);
    ASSERT_EQ(plan.variants.size(), 2u * 3u * 2u);
    // First axis slowest, seeds fastest; seeds are the scene's + 0, 1.
    EXPECT_EQ(plan.variants[0].overridesText(), "charges[0].tnt_kg=1;objects[0].material=\"concrete\"");
    EXPECT_EQ(plan.variants[1].seed, 41u);
    EXPECT_EQ(plan.variants[2].overridesText(), "charges[0].tnt_kg=1;objects[0].material=\"wood\"");
    EXPECT_EQ(plan.variants[11].overridesText(), "charges[0].tnt_kg=2.5;objects[0].material=\"glass\"");
    EXPECT_EQ(plan.variants[11].name(), "v0011");
    const nlohmann::json scene = variantScene(plan, plan.variants[11]);
    EXPECT_EQ(scene["charges"][0]["tnt_kg"], 2.5);
    EXPECT_EQ(scene["objects"][0]["material"], "glass");
    EXPECT_EQ(scene["seed"], 41);
}

TEST(Sweep, ABadKeyOrValueIsRefusedNamingTheVariantAndTheKey)
{
    const std::string scene = writeScene("bad");
    const auto refusal = [&](const std::string& axis) {
        try {
            planSweep(scene, {parseSweepAxis(axis)}, 0);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_NE(refusal("charges[0].tnt_kg=1,-3").find("v0001 (charges[0].tnt_kg=-3)"), std::string::npos) << refusal("charges[0].tnt_kg=1,-3");
    EXPECT_NE(refusal("charges[0].tnt_kg=1,-3").find("tnt_kg"), std::string::npos);
    EXPECT_NE(refusal("charges[2].tnt_kg=1").find("charges[2].tnt_kg: the scene has no charges[2] (it lists 1)"), std::string::npos)
        << refusal("charges[2].tnt_kg=1");
    EXPECT_NE(refusal("solver.no_such_key=1").find("no_such_key"), std::string::npos) << refusal("solver.no_such_key=1");
    EXPECT_THROW(parseSweepAxis("charges[0].tnt_kg"), InputError);
}

TEST(Sweep, ManifestReadsBackAsTheSamePlan)
{
    const std::string scene = writeScene("manifest");
    const SweepPlan plan = planSweep(scene, {parseSweepAxis("charges[0].tnt_kg=1,2")}, 3);
    const std::string dir = std::filesystem::path(scene).parent_path().string();
    writeSweepPlan(dir, plan);
    const SweepPlan back = readSweepPlan(dir);
    EXPECT_TRUE(samePlan(plan, back));
    ASSERT_EQ(back.variants.size(), plan.variants.size());
    for (size_t i = 0; i < plan.variants.size(); ++i) {
        EXPECT_EQ(back.variants[i].seed, plan.variants[i].seed);
        EXPECT_EQ(back.variants[i].overridesText(), plan.variants[i].overridesText());
    }
    EXPECT_FALSE(samePlan(plan, planSweep(scene, {parseSweepAxis("charges[0].tnt_kg=1,3")}, 3)));
}

TEST(Sweep, ConfidenceIntervalIsStudentsT)
{
    // {1, 2, 3, 4}: mean 2.5, s = sqrt(5/3), t(0.975, 3) = 3.182: half width 3.182 s / 2 = 2.054.
    const MeanInterval m = meanInterval({1, 2, 3, 4});
    EXPECT_DOUBLE_EQ(m.mean, 2.5);
    EXPECT_NEAR(m.halfWidth, 3.182 * std::sqrt(5.0 / 3.0) / 2, 1e-12);
    EXPECT_EQ(m.min, 1);
    EXPECT_EQ(m.max, 4);
    EXPECT_TRUE(std::isnan(meanInterval({7}).halfWidth));
    // Many values: the normal quantile's limit.
    std::vector<double> many(10000);
    for (size_t i = 0; i < many.size(); ++i) many[i] = double(i % 2);
    EXPECT_NEAR(meanInterval(many).halfWidth, 1.96 * 0.5 / 100, 2e-4);
}

TEST(Sweep, AFailedVariantIsReportedWithItsReasonAndTheOthersStillCount)
{
    const std::string scene = writeScene("failed");
    const std::string dir = std::filesystem::path(scene).parent_path().string() + "/sweep";
    std::filesystem::create_directories(dir);
    // The second variant's voxels (0.3 m box at 1 mm) exceed max_voxels when voxelised.
    const SweepPlan plan = planSweep(scene, {parseSweepAxis("voxel_size_m=0.1,0.001")}, 0);
    writeSweepPlan(dir, plan);
    EXPECT_EQ(runSweepVariant(dir, plan, 0, nullptr), VariantState::Done);
    EXPECT_EQ(runSweepVariant(dir, plan, 1, nullptr), VariantState::Failed);
    const SweepSummary s = collectSweep(dir, plan);
    EXPECT_EQ(s.status[0].state, VariantState::Done);
    EXPECT_GT(s.figures[0].fragments, 0);
    EXPECT_EQ(s.status[1].state, VariantState::Failed);
    EXPECT_NE(s.status[1].message.find("max_voxels"), std::string::npos) << s.status[1].message;
    writeSweepSummary(dir, plan, s);
    std::ifstream csv(dir + "/summary.csv");
    std::string header, first, second;
    std::getline(csv, header);
    std::getline(csv, first);
    std::getline(csv, second);
    EXPECT_NE(first.find(",done,"), std::string::npos) << first;
    EXPECT_NE(second.find(",failed,"), std::string::npos) << second;
    EXPECT_NE(second.find("max_voxels"), std::string::npos) << second;
}
