// libFuzzer target: the scene parser. Any input must either parse or throw InputError naming the
// problem; a crash, a sanitizer report or any other exception is a bug (docs/testing.md).
#include <spall/core/Error.h>
#include <spall/scene/Scene.h>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const spall::Scene scene = spall::parseScene(text, "fuzz.json", "/nonexistent");
        // What parses must write back and parse again.
        spall::parseScene(spall::sceneToJson(scene).dump(), "fuzz-resolved.json", "/nonexistent");
    } catch (const spall::InputError&) {
    }
    return 0;
}
