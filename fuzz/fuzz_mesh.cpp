// libFuzzer target: the mesh import path (assimp, then spall's checks and voxelisation). Any input
// must either voxelise or throw InputError; a crash, a sanitizer report or any other exception is a
// bug (docs/testing.md). The input is written to a file because assimp picks its importer from the
// extension: the first byte chooses one of the formats spall documents.
#include <spall/core/Error.h>
#include <spall/voxel/Voxelise.h>

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1) return 0;
    static const char* const kExtensions[] = {".obj", ".stl", ".ply", ".off", ".gltf"};
    const std::string path = "/tmp/spall_fuzz_mesh_" + std::to_string(getpid()) + kExtensions[data[0] % 5];
    if (FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(data + 1, 1, size - 1, f);
        std::fclose(f);
    } else {
        return 0;
    }
    try {
        spall::VoxeliseSettings settings;
        settings.voxelSizeM = 0.05;
        settings.maxVoxels = 100000;  // bounded work per input
        spall::voxeliseMesh(spall::loadMesh(path), settings, path);
    } catch (const spall::InputError&) {
    }
    std::remove(path.c_str());
    return 0;
}
