// Golden values: the hash of the whole state (stateHash) at the last frame of shipped scenes, run
// as `spall run` runs them (landing on every frame's time). A refactor leaves them as they are; a
// deliberate change of the physics or of a scene updates them in the same commit and says why.
#include <spall/scene/Scene.h>
#include <spall/sim/Simulation.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

using namespace spall;

namespace {

uint64_t lastFrameStateHash(const std::string& sceneName)
{
    const Scene scene = loadScene(SPALL_SOURCE_DIR "/assets/scenes/" + sceneName);
    Simulation sim(scene);
    for (int f = 0; f < scene.frameCount(); ++f) sim.advanceTo(f / scene.frameRateHz);
    return stateHash(sim.state());
}

std::string hex(uint64_t value)
{
    char text[32];
    std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(value));
    return text;
}

}  // namespace

TEST(Golden, TheDefaultSceneEndsInItsRecordedState)
{
    EXPECT_EQ(hex(lastFrameStateHash("default.json")), "0xd0fbc8d53782bd22");
}

TEST(Golden, TheGlassSceneEndsInItsRecordedState)
{
    EXPECT_EQ(hex(lastFrameStateHash("glass-pane.json")), "0x6124667b8f9cba95");
}
