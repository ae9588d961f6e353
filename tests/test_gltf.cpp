// The glTF export read back by tinygltf and checked against the run's history.h5 (written from
// the bodies in memory, not from the frames the export reads).
#include "TestUtil.h"

#include <spall/fracture/Fracture.h>
#include <spall/output/FrameWriter.h>
#include <spall/output/GltfExport.h>
#include <spall/output/History.h>
#include <spall/scene/Scene.h>
#include <spall/run/Run.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <map>
#include <set>

using namespace spall;

namespace {

std::vector<float> floatsOf(const tinygltf::Model& model, int accessorIndex)
{
    const tinygltf::Accessor& a = model.accessors.at(accessorIndex);
    const tinygltf::BufferView& view = model.bufferViews.at(a.bufferView);
    const size_t components = tinygltf::GetNumComponentsInType(a.type);
    const auto* data = reinterpret_cast<const float*>(model.buffers.at(view.buffer).data.data() + view.byteOffset + a.byteOffset);
    return std::vector<float>(data, data + a.count * components);
}

std::vector<uint32_t> indicesOf(const tinygltf::Model& model, int accessorIndex)
{
    const tinygltf::Accessor& a = model.accessors.at(accessorIndex);
    const tinygltf::BufferView& view = model.bufferViews.at(a.bufferView);
    const auto* data = reinterpret_cast<const uint32_t*>(model.buffers.at(view.buffer).data.data() + view.byteOffset + a.byteOffset);
    return std::vector<uint32_t>(data, data + a.count);
}

/// A node's animated value at time t (LINEAR or STEP, clamped at the ends), as glTF 2.0 §3.11 defines.
std::vector<float> sampleAt(const tinygltf::Model& model, int node, const std::string& path, float t)
{
    for (const auto& animation : model.animations)
        for (const auto& channel : animation.channels) {
            if (channel.target_node != node || channel.target_path != path) continue;
            const auto& sampler = animation.samplers.at(channel.sampler);
            const std::vector<float> times = floatsOf(model, sampler.input), values = floatsOf(model, sampler.output);
            const size_t n = values.size() / times.size();
            size_t i = 0;
            while (i + 1 < times.size() && times[i + 1] <= t) ++i;
            float s = 0.0f;  // the fraction of the way to the next key (STEP and the ends: none)
            if (sampler.interpolation == "LINEAR" && i + 1 < times.size() && t > times[i]) s = (t - times[i]) / (times[i + 1] - times[i]);
            std::vector<float> out(n);
            for (size_t c = 0; c < n; ++c) out[c] = values[i * n + c] + (s > 0 ? s * (values[(i + 1) * n + c] - values[i * n + c]) : 0.0f);
            return out;
        }
    return {};
}

double triangleArea(const std::vector<float>& p, const std::vector<uint32_t>& idx, size_t t)
{
    auto at = [&](uint32_t i) { return Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]); };
    return 0.5 * (at(idx[t + 1]) - at(idx[t])).cross(at(idx[t + 2]) - at(idx[t])).norm();
}

/// Area of a mesh's triangles by material name.
std::map<std::string, double> areaByMaterial(const tinygltf::Model& model, const tinygltf::Mesh& mesh)
{
    std::map<std::string, double> area;
    for (const auto& primitive : mesh.primitives) {
        const std::vector<float> p = floatsOf(model, primitive.attributes.at("POSITION"));
        const std::vector<uint32_t> idx = indicesOf(model, primitive.indices);
        for (size_t t = 0; t + 2 < idx.size(); t += 3) area[model.materials.at(primitive.material).name] += triangleArea(p, idx, t);
    }
    return area;
}

/// An empty scratch directory of that name.
std::string freshDirectory(const std::string& name)
{
    const std::string dir = (std::filesystem::temp_directory_path() / name).string();
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// DIR's frames exported to DIR/debris.glb and read back (empty, and a failure, when it does not read).
tinygltf::Model exportAndRead(const std::string& dir)
{
    exportGltf(dir, dir + "/debris.glb");
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, dir + "/debris.glb")) << error;
    return model;
}

double meshVolume(const tinygltf::Model& model, const tinygltf::Mesh& mesh)
{
    double volume = 0.0;
    for (const auto& primitive : mesh.primitives) {
        const std::vector<float> p = floatsOf(model, primitive.attributes.at("POSITION"));
        const std::vector<uint32_t> idx = indicesOf(model, primitive.indices);
        for (size_t t = 0; t + 2 < idx.size(); t += 3) {
            const Eigen::Vector3d a(p[3 * idx[t]], p[3 * idx[t] + 1], p[3 * idx[t] + 2]), b(p[3 * idx[t + 1]], p[3 * idx[t + 1] + 1], p[3 * idx[t + 1] + 2]),
                c(p[3 * idx[t + 2]], p[3 * idx[t + 2] + 1], p[3 * idx[t + 2] + 2]);
            volume += a.dot(b.cross(c)) / 6.0;
        }
    }
    return volume;
}

}  // namespace

TEST(Gltf, EachFragmentIsANodeThatFollowsTheHistoryWithAMeshOfItsVolume)
{
    const std::string dir = (std::filesystem::temp_directory_path() / "spall_test_gltf").string();
    std::filesystem::remove_all(dir);
    const Scene scene = parseScene(R"({
      "voxel_size_m": 0.1, "duration_s": 0.25, "frame_rate_hz": 24, "seed": 3,
      "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [2.0, 0.3, 1.5]},
                   "position_m": [0, 0, 0.75], "material": "brick-masonry", "anchor": "ground"}],
      "charges": [{"position_m": [0.2, -2.0, 0.0], "tnt_kg": 4.0, "burst": "surface"}]})", "gltf-scene", ".");
    RunOptions options;
    options.outputDirectory = dir;
    options.gltfPath = dir + "/debris.glb";  // the run's glTF sink exports once the run completes
    const RunReport run = runScene(scene, options, {});
    ASSERT_TRUE(run.complete);
    ASSERT_TRUE(run.gltf.has_value());
    const GltfExportReport report = *run.gltf;
    EXPECT_FALSE(std::filesystem::exists(dir + "/debris.glb.partial." + std::to_string(getpid())));

    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, dir + "/debris.glb")) << error;
    EXPECT_EQ(int(model.nodes.size()), report.nodes + report.charges);
    // The wall's material, its own surface and its cracks' (through bricks, along joints).
    ASSERT_GE(model.materials.size(), 2u);
    for (const tinygltf::Material& m : model.materials) EXPECT_EQ(m.name.rfind("brick-masonry", 0), 0u) << m.name;
    std::map<std::string, int> nodeByName;
    for (size_t i = 0; i < model.nodes.size(); ++i) nodeByName[model.nodes[i].name] = int(i);
    // The charge: an empty node where the scene put it, in glTF's Y-up axes (x, z, -y), with its mass.
    ASSERT_EQ(report.charges, 1);
    ASSERT_TRUE(nodeByName.count("charge_0"));
    const tinygltf::Node& charge = model.nodes[nodeByName["charge_0"]];
    EXPECT_EQ(charge.mesh, -1);
    ASSERT_EQ(charge.translation.size(), 3u);
    EXPECT_NEAR(charge.translation[0], 0.2, 1e-6);
    EXPECT_NEAR(charge.translation[1], 0.0, 1e-6);
    EXPECT_NEAR(charge.translation[2], 2.0, 1e-6);
    EXPECT_DOUBLE_EQ(charge.extras.Get("tnt_kg").GetNumberAsDouble(), 4.0);

    const History h = readHistory(dir + "/history.h5");
    const int frames = int(h.timeS.size());
    ASSERT_EQ(frames, report.frames);
    std::map<int64_t, int> firstFrame;
    std::map<int, double> volumeOfMesh;
    std::set<int> shapesShown;
    for (int f = 0; f < frames; ++f)
        for (int64_t row = h.bodyOffset[f]; row < h.bodyOffset[f + 1]; ++row) {
            const int64_t id = h.bodyId[row];
            firstFrame.emplace(id, f);
            ASSERT_TRUE(nodeByName.count("fragment_" + std::to_string(id))) << id;
            const int node = nodeByName["fragment_" + std::to_string(id)];
            // Where the history puts the centre of mass, in glTF's Y-up axes: (x, z, -y).
            const Eigen::Vector3d& p = h.bodyPositionM[row];
            const std::vector<float> t = sampleAt(model, node, "translation", float(h.timeS[f]));
            ASSERT_EQ(t.size(), 3u);
            EXPECT_LT((Eigen::Vector3d(t[0], t[1], t[2]) - Eigen::Vector3d(p.x(), p.z(), -p.y())).norm(), 1e-3) << id << " at frame " << f;
            const std::vector<float> scale = sampleAt(model, node, "scale", float(h.timeS[f]));
            EXPECT_TRUE(scale.empty() || scale[0] == 1.0f) << id << " is hidden at frame " << f << " while it lives";
            if (f > 0 && firstFrame[id] == f) {
                EXPECT_EQ(sampleAt(model, node, "scale", float(h.timeS[f - 1])).at(0), 0.0f) << id << " shows before its first frame";
            }
            // At every frame the shape shown has the body's voxels' volume (a body changes shape
            // only by splitting, and its parts get new ids).
            const int mesh = model.nodes[node].mesh;
            if (!volumeOfMesh.count(mesh)) volumeOfMesh[mesh] = meshVolume(model, model.meshes.at(mesh));
            const double voxels = h.bodyVoxelCount[row] * std::pow(scene.voxelSizeM, 3);
            EXPECT_NEAR(volumeOfMesh[mesh], voxels, 0.1 * voxels) << id << " at frame " << f;
            shapesShown.insert(mesh);
        }
    int fractured = 0;
    for (const int mesh : shapesShown)
        for (const auto& primitive : model.meshes[mesh].primitives) fractured += model.materials.at(primitive.material).name != "brick-masonry";
    EXPECT_GT(firstFrame.size(), 5u) << "the wall should have broken";
    EXPECT_GT(fractured, 0) << "no piece shows fracture surface";
    std::printf("%d nodes, %d meshes, %lld triangles, %.2f MB\n", report.nodes, report.meshes, static_cast<long long>(report.triangles),
                report.bytes / 1e6);
}

TEST(Gltf, FractureMaterialCoversExactlyTheFacesThatBroke)
{
    initialiseOpenVdb();
    // A 4 x 1 x 1 bar broken between voxels 1 and 2, turned about a skew axis: each half has
    // 10 faces of 0.01 m^2, one of them fracture surface, with and without fracture roughness.
    for (const double roughness : {0.0, 0.2}) {
        const std::vector<Body> halves = test::barBrokenInTwo(
            test::boxBody(4, 1, 1, 0.1, 1000.0, Eigen::Vector3d(0.3, -0.2, 0.5),
                          Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()))),
            1);
        ASSERT_EQ(halves.size(), 2u);
        const std::string dir = freshDirectory("spall_test_gltf_fracture");
        OutputSettings settings;
        settings.fractureRoughnessVoxels = roughness;
        FrameWriter(dir, settings, {findMaterialPreset("concrete")}).write({0, 0.0}, halves);
        const tinygltf::Model model = exportAndRead(dir);
        ASSERT_EQ(model.meshes.size(), 2u);
        for (const tinygltf::Mesh& mesh : model.meshes) {
            std::map<std::string, double> area = areaByMaterial(model, mesh);
            std::printf("roughness %.1f: outer %.5f m^2, fracture %.5f m^2\n", roughness, area["concrete"], area["concrete interior"]);
            // Roughness wrinkles the broken face, adding a little area to it.
            EXPECT_NEAR(area["concrete interior"], 0.01, roughness > 0 ? 0.003 : 1e-6) << mesh.name;
            EXPECT_NEAR(area["concrete"], 0.09, 1e-6) << mesh.name;
        }
    }
}

TEST(Gltf, AMasonryCrackShowsMortarAlongAJointAndBrickThroughAUnit)
{
    initialiseOpenVdb();
    // A bar of brick masonry along x in the bottom course, 2.5 cm voxels at index times h: the
    // running bond's first course has a unit every 0.215 + 0.010 m from x = 0 (the preset's
    // brick and joint), so voxels 8 (x = 0.200 m) and 9 (0.225 m) lie in different bricks and 3
    // and 4 in the same one. A break between 8 and 9 shows mortar on both halves, one between 3
    // and 4 the brick's interior.
    const Material brick = findMaterialPreset("brick-masonry");
    for (const auto& [breakAfter, expected] : {std::pair{8, "brick-masonry joint"}, std::pair{3, "brick-masonry interior"}}) {
        Body bar = test::boxBody(10, 1, 1, 0.025, 1900.0, Eigen::Vector3d(0.125, 0, 0.0125));
        auto acc = bar.grid->getAccessor();
        breakLink(acc, openvdb::Coord(breakAfter, 0, 0), kPosX);
        std::vector<Body> halves = splitBody(bar);
        ASSERT_EQ(halves.size(), 2u);
        for (size_t i = 0; i < halves.size(); ++i) halves[i].id = int64_t(i);
        const std::string dir = freshDirectory("spall_test_gltf_joint");
        FrameWriter(dir, OutputSettings{}, {brick}).write({0, 0.0}, halves);
        const tinygltf::Model model = exportAndRead(dir);
        for (const tinygltf::Mesh& mesh : model.meshes) {
            std::map<std::string, double> area = areaByMaterial(model, mesh);
            EXPECT_NEAR(area[expected], 0.025 * 0.025, 1e-4 * 0.025 * 0.025) << mesh.name << " broken after voxel " << breakAfter;
            EXPECT_EQ(area.size(), 2u) << mesh.name << ": only the brick's own surface and the break";
        }
        // Each surface in the preset's colours: a brick's red outside, the mortar's grey.
        for (const tinygltf::Material& m : model.materials) {
            const Eigen::Vector3d& colour = m.name == "brick-masonry" ? brick.colourRgb : m.name == "brick-masonry joint" ? brick.jointColourRgb : brick.interiorColourRgb;
            for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(m.pbrMetallicRoughness.baseColorFactor[c], colour[c]) << m.name;
        }
    }
}

namespace {

/// Per undirected edge of a mesh's triangles (all primitives), how many triangles use it.
std::map<std::pair<uint32_t, uint32_t>, int> edgeUses(const tinygltf::Model& model, const tinygltf::Mesh& mesh)
{
    std::map<std::pair<uint32_t, uint32_t>, int> uses;
    for (const auto& primitive : mesh.primitives) {
        const std::vector<uint32_t> idx = indicesOf(model, primitive.indices);
        for (size_t t = 0; t + 2 < idx.size(); t += 3)
            for (int e = 0; e < 3; ++e) {
                const uint32_t a = idx[t + e], b = idx[t + (e + 1) % 3];
                ++uses[{std::min(a, b), std::max(a, b)}];
            }
    }
    return uses;
}

int64_t triangleCount(const tinygltf::Model& model, const tinygltf::Mesh& mesh)
{
    int64_t n = 0;
    for (const auto& primitive : mesh.primitives) n += int64_t(model.accessors.at(primitive.indices).count / 3);
    return n;
}

}  // namespace

TEST(Gltf, APieceOverItsTriangleBudgetIsMeshedAdaptivelyAndStaysAClosedSolid)
{
    initialiseOpenVdb();
    // A brick of 9 x 4 x 3 voxels of 2.5 cm broken off a bar: exact, its faces are a fine grid of
    // triangles (three level-set samples per voxel edge); within the default budget of 1000 the
    // mesher merges the flat faces. Either way the mesh is closed (every edge between two
    // triangles) and holds the brick's volume within 1 %, and its broken face keeps its material
    // (within 5 % of its area: merged triangles near its rim may fall either side).
    Body bar = test::boxBody(12, 4, 3, 0.025, 1900.0, Eigen::Vector3d(0.2, 0, 0.04));
    auto acc = bar.grid->getAccessor();
    for (int y = 0; y < 4; ++y)
        for (int z = 0; z < 3; ++z) breakLink(acc, openvdb::Coord(8, y, z), kPosX);
    std::vector<Body> parts = splitBody(bar);
    ASSERT_EQ(parts.size(), 2u);
    for (size_t i = 0; i < parts.size(); ++i) parts[i].id = int64_t(i);
    const Body& brick = parts[0].mass.voxelCount == 9 * 4 * 3 ? parts[0] : parts[1];

    int64_t exactTriangles = 0;
    for (const int64_t budget : {int64_t{0}, int64_t{1000}}) {
        const std::string dir = freshDirectory("spall_test_gltf_budget");
        Scene scene = parseScene(R"({"objects": [{"name": "b", "primitive": {"shape": "box", "size_m": [0.1, 0.1, 0.1]},
                                                   "position_m": [0, 0, 0.05], "material": "concrete"}],
                                      "charges": [{"position_m": [1, 0, 0.1], "tnt_kg": 1}]})", "budget", ".");
        scene.output.gltfMaxTrianglesPerPiece = budget;
        std::ofstream(dir + "/scene.json") << sceneToJson(scene).dump();
        FrameWriter(dir, OutputSettings{}, {findMaterialPreset("concrete")}).write({0, 0.0}, {brick});
        const tinygltf::Model model = exportAndRead(dir);
        ASSERT_EQ(model.meshes.size(), 1u);
        const tinygltf::Mesh& mesh = model.meshes[0];
        const int64_t triangles = triangleCount(model, mesh);
        const double volume = 9 * 4 * 3 * std::pow(0.025, 3), interior = 4 * 3 * 0.025 * 0.025;
        const double volumeRatio = meshVolume(model, mesh) / volume, interiorRatio = areaByMaterial(model, mesh)["concrete interior"] / interior;
        std::printf("budget %lld: %lld triangles, volume x %.4f, broken face's area x %.4f\n", static_cast<long long>(budget),
                    static_cast<long long>(triangles), volumeRatio, interiorRatio);
        if (budget == 0) exactTriangles = triangles;
        else {
            EXPECT_LE(triangles, budget);
            EXPECT_LT(triangles, exactTriangles / 3);
        }
        for (const auto& [edge, uses] : edgeUses(model, mesh)) ASSERT_EQ(uses, 2) << "edge " << edge.first << "-" << edge.second;
        EXPECT_NEAR(volumeRatio, 1.0, 0.01);
        EXPECT_NEAR(interiorRatio, 1.0, 0.05);
    }
}
