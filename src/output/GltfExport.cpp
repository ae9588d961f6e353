#include <spall/output/GltfExport.h>

#include <spall/core/AtomicFile.h>
#include <spall/core/Error.h>
#include <spall/core/Parallel.h>
#include <spall/output/FragmentSurface.h>
#include <spall/output/FrameWriter.h>
#include <spall/output/RunScene.h>
#include <spall/voxel/VdbIo.h>
#include <spall/voxel/LinkBits.h>

#include <openvdb/io/File.h>
#include <tiny_gltf.h>

#include <Eigen/Geometry>

#include <array>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <unordered_map>

namespace spall {

namespace {

// glTF is Y-up, spall Z-up: a rotation of -90° about x, (x, y, z) -> (x, z, -y); a rotation's
// axis turns the same way (C q C⁻¹).
Eigen::Vector3f toYUp(const Eigen::Vector3d& v) { return Eigen::Vector3f(float(v.x()), float(v.z()), float(-v.y())); }
Eigen::Quaternionf toYUp(const Eigen::Quaterniond& q)
{
    return Eigen::Quaternionf(float(q.w()), float(q.x()), float(q.z()), float(-q.y())).normalized();
}

/// The surfaces a piece's triangles show, each a glTF material of the piece's own material.
enum Surface { kOuterSurface, kInteriorSurface, kJointSurface, kSurfaceCount };
const char* const kSurfaceSuffix[kSurfaceCount] = {"", " interior", " joint"};

struct PieceMesh {
    std::vector<Eigen::Vector3f> positions;  ///< body frame, pivot at the centre of mass, Y-up (unit: m)
    /// Triangles, counter-clockwise seen from outside, by surface: the object's own, a crack
    /// through the material (or through a masonry unit), a crack along a joint.
    std::array<std::vector<uint32_t>, kSurfaceCount> triangles;
    std::string material;                    ///< the scene material's name; "" when the frames do not say
};

struct Pose {
    float timeS;
    Eigen::Vector3f position;
    Eigen::Quaternionf rotation;
    bool operator==(const Pose& o) const { return position == o.position && rotation.coeffs() == o.rotation.coeffs(); }
};

struct Track {
    int mesh = -1;
    int firstFrame = -1, lastFrame = -1;
    std::vector<Pose> poses;
};

/// What a fragment grid's metadata says of its body's pose.
struct FragmentPose {
    int64_t id;
    uint64_t meshKey;
    Eigen::Vector3d centreOfMassM;
    Eigen::Quaterniond orientation;
    double voxelSizeM;
    std::string material;
};

FragmentPose poseOf(const openvdb::GridBase& grid, const std::string& path)
{
    try {
        const openvdb::Vec3d c = grid.metaValue<openvdb::Vec3d>("centre_of_mass_m");
        const openvdb::Vec4d q = grid.metaValue<openvdb::Vec4d>("orientation_xyzw");
        const auto material = grid.getMetadata<openvdb::StringMetadata>("material");
        return {grid.metaValue<int64_t>("body_id"), static_cast<uint64_t>(grid.metaValue<int64_t>("mesh_key")), {c.x(), c.y(), c.z()},
                Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(), grid.metaValue<double>("voxel_size_m"),
                material ? material->value() : std::string()};
    } catch (const std::exception& e) {
        throw InputError(path + ": " + grid.getName() + ": metadata of a spall frame missing (" + e.what() + ")");
    }
}

/// The surface a mesh triangle shows: that of its normal's largest component in the body's axes,
/// of the voxel 0.45 voxel inward from its centroid along that axis (stepping along the axis, not
/// the tilted normal, keeps a rough face's rim in its voxel), from its bits in fracture_faces.
Surface surfaceOf(const openvdb::FloatGrid& fractureFaces, const Eigen::Vector3d& centroidWorld, const Eigen::Vector3d& normalWorld,
                  const Eigen::Matrix3d& worldToBody)
{
    const Eigen::Vector3d n = worldToBody * normalWorld;
    int axis = 0;
    n.cwiseAbs().maxCoeff(&axis);
    const int face = 2 * axis + (n[axis] > 0 ? 1 : 0);
    openvdb::Vec3d inside = fractureFaces.transform().worldToIndex(openvdb::Vec3d(centroidWorld.x(), centroidWorld.y(), centroidWorld.z()));
    inside[axis] -= 0.45 * faceSign(face);
    // Voxel centres lie at integer indices: round (OpenVDB's "node-centred" floors).
    const int bits = int(fractureFaces.tree().getValue(openvdb::Coord::round(inside)));
    if (!((bits >> face) & 1)) return kOuterSurface;
    return (bits >> (kJointFaceBit + face)) & 1 ? kJointSurface : kInteriorSurface;
}

/// The fragment's level set meshed (adaptivity 0) in its body frame, triangles split by material.
/// The level set meshed exactly, or where that passes `maxTriangles` (0: no limit) at the least
/// adaptivity that fits, found to 1/64 by bisection (at most 1, which may still not fit): the
/// least merging keeps the most of the shape.
SurfaceMesh meshWithin(const openvdb::FloatGrid& levelSet, int64_t maxTriangles)
{
    SurfaceMesh exact = meshLevelSet(levelSet);
    if (maxTriangles <= 0 || int64_t(exact.triangles.size()) <= maxTriangles) return exact;
    double fits = 1.0, tooMany = 0.0;
    SurfaceMesh best = meshLevelSet(levelSet, fits);
    if (int64_t(best.triangles.size()) > maxTriangles) return best;
    for (int i = 0; i < 6; ++i) {
        const double adaptivity = 0.5 * (fits + tooMany);
        SurfaceMesh mesh = meshLevelSet(levelSet, adaptivity);
        if (int64_t(mesh.triangles.size()) <= maxTriangles) fits = adaptivity, best = std::move(mesh);
        else tooMany = adaptivity;
    }
    return best;
}

PieceMesh meshPiece(const openvdb::FloatGrid& levelSet, const openvdb::FloatGrid* fractureFaces, const FragmentPose& pose, int64_t maxTriangles)
{
    const SurfaceMesh surface = meshWithin(levelSet, maxTriangles);
    const std::vector<Eigen::Vector3d>& world = surface.pointsM;
    const bool flip = surface.signedVolumeM3() < 0.0;  // glTF wants triangles wound outward
    const Eigen::Matrix3d worldToBody = pose.orientation.toRotationMatrix().transpose();
    PieceMesh mesh;
    mesh.material = pose.material;
    mesh.positions.reserve(world.size());
    for (const Eigen::Vector3d& p : world) mesh.positions.push_back(toYUp(worldToBody * (p - pose.centreOfMassM)));
    for (auto t : surface.triangles) {
        if (flip) std::swap(t[1], t[2]);
        const Eigen::Vector3d normal = (world[t[1]] - world[t[0]]).cross(world[t[2]] - world[t[0]]);
        if (normal.norm() < 1e-12 * pose.voxelSizeM * pose.voxelSizeM) continue;  // degenerate
        const Eigen::Vector3d centroid = (world[t[0]] + world[t[1]] + world[t[2]]) / 3.0;
        const Surface surface = fractureFaces ? surfaceOf(*fractureFaces, centroid, normal.normalized(), worldToBody) : kOuterSurface;
        mesh.triangles[surface].insert(mesh.triangles[surface].end(), t.begin(), t.end());
    }
    return mesh;
}

/// Appends typed arrays to the model's one buffer, a view and an accessor each.
class BufferPacker {
public:
    explicit BufferPacker(tinygltf::Model& model) : mModel(model) { mModel.buffers.resize(1); }

    template <typename T>
    int add(const std::vector<T>& values, int componentType, int type, size_t count, int target = 0,
            std::vector<double> minValues = {}, std::vector<double> maxValues = {})
    {
        auto& bytes = mModel.buffers[0].data;
        bytes.resize((bytes.size() + 3) / 4 * 4, 0);  // every view 4-byte aligned
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = bytes.size();
        view.byteLength = values.size() * sizeof(T);
        view.target = target;
        const auto* data = reinterpret_cast<const unsigned char*>(values.data());
        bytes.insert(bytes.end(), data, data + view.byteLength);
        mModel.bufferViews.push_back(view);
        tinygltf::Accessor accessor;
        accessor.bufferView = int(mModel.bufferViews.size()) - 1;
        accessor.componentType = componentType;
        accessor.type = type;
        accessor.count = count;
        accessor.minValues = std::move(minValues);
        accessor.maxValues = std::move(maxValues);
        mModel.accessors.push_back(accessor);
        return int(mModel.accessors.size()) - 1;
    }

    int vec3(const std::vector<Eigen::Vector3f>& v, int target = 0)
    {
        Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
        std::vector<float> flat;
        flat.reserve(3 * v.size());
        for (const auto& p : v) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
            flat.insert(flat.end(), {p.x(), p.y(), p.z()});
        }
        return add(flat, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, v.size(), target, {lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()});
    }

    int times(const std::vector<float>& t)
    {
        return add(t, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, t.size(), 0, {double(t.front())}, {double(t.back())});
    }

private:
    tinygltf::Model& mModel;
};

/// The glTF material of a scene material's surface: its colour, the interior's or the joint's;
/// glass lets light through (KHR_materials_transmission).
int addMaterial(tinygltf::Model& model, const Material& material, Surface surface)
{
    const Eigen::Vector3d& colour = surface == kOuterSurface ? material.colourRgb : surface == kJointSurface ? material.jointColourRgb : material.interiorColourRgb;
    tinygltf::Material m;
    m.name = material.name + kSurfaceSuffix[surface];
    m.pbrMetallicRoughness.baseColorFactor = {colour.x(), colour.y(), colour.z(), 1.0};
    m.pbrMetallicRoughness.metallicFactor = 0.0;
    // A fresh break is rougher than a weathered or glazed face (glass's edges stay fairly smooth).
    m.pbrMetallicRoughness.roughnessFactor = surface == kOuterSurface ? material.roughness : std::min(1.0, material.roughness + 0.25);
    if (material.transmission > 0) {
        m.extensions["KHR_materials_transmission"] = tinygltf::Value(tinygltf::Value::Object{{"transmissionFactor", tinygltf::Value(material.transmission)}});
        if (std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), "KHR_materials_transmission") == model.extensionsUsed.end())
            model.extensionsUsed.push_back("KHR_materials_transmission");
    }
    model.materials.push_back(m);
    return int(model.materials.size()) - 1;
}

/// Each piece a mesh with a primitive per surface it shows, in its material's looks (`looks`:
/// the scene's materials by name).
void addMeshes(tinygltf::Model& model, BufferPacker& packer, const std::vector<PieceMesh>& pieces,
               const std::map<std::string, Material>& looks, GltfExportReport& report)
{
    std::map<std::pair<std::string, int>, int> materials;  // (material, surface) -> glTF material
    for (size_t i = 0; i < pieces.size(); ++i) {
        const PieceMesh& piece = pieces[i];
        tinygltf::Mesh mesh;
        mesh.name = "piece_" + std::to_string(i);
        const int positions = packer.vec3(piece.positions, TINYGLTF_TARGET_ARRAY_BUFFER);
        for (int surface = 0; surface < kSurfaceCount; ++surface) {
            const std::vector<uint32_t>& indices = piece.triangles[surface];
            if (indices.empty()) continue;
            auto [known, isNew] = materials.emplace(std::pair{piece.material, surface}, -1);
            if (isNew) known->second = addMaterial(model, looks.at(piece.material), Surface(surface));
            tinygltf::Primitive primitive;
            primitive.attributes["POSITION"] = positions;
            primitive.indices = packer.add(indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, indices.size(),
                                           TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
            primitive.material = known->second;
            primitive.mode = TINYGLTF_MODE_TRIANGLES;
            mesh.primitives.push_back(primitive);
            report.triangles += int64_t(indices.size() / 3);
        }
        model.meshes.push_back(mesh);
    }
}

/// One animation channel with its own sampler.
void addChannel(tinygltf::Animation& animation, int node, const char* path, int input, int output, const char* interpolation)
{
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = output;
    sampler.interpolation = interpolation;
    animation.samplers.push_back(sampler);
    tinygltf::AnimationChannel channel;
    channel.sampler = int(animation.samplers.size()) - 1;
    channel.target_node = node;
    channel.target_path = path;
    animation.channels.push_back(channel);
}

/// A fragment's pose channels: a sample equal to both neighbours is dropped (exact under linear
/// interpolation), so resting bodies cost two samples. Returns the samples kept.
int64_t addPoseChannels(tinygltf::Animation& animation, BufferPacker& packer, int node, const std::vector<Pose>& poses)
{
    std::vector<float> times, rotations;
    std::vector<Eigen::Vector3f> positions;
    for (size_t i = 0; i < poses.size(); ++i) {
        if (i > 0 && i + 1 < poses.size() && poses[i] == poses[i - 1] && poses[i] == poses[i + 1]) continue;
        const Pose& p = poses[i];
        times.push_back(p.timeS);
        positions.push_back(p.position);
        rotations.insert(rotations.end(), {p.rotation.x(), p.rotation.y(), p.rotation.z(), p.rotation.w()});
    }
    const int input = packer.times(times);
    addChannel(animation, node, "translation", input, packer.vec3(positions), "LINEAR");
    addChannel(animation, node, "rotation", input, packer.add(rotations, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, times.size()),
               "LINEAR");
    return int64_t(times.size());
}

/// Scale 1 from a fragment's first frame to its last, 0 before and after (none if it lives
/// through the run).
void addVisibilityChannel(tinygltf::Animation& animation, BufferPacker& packer, int node, const Track& track,
                          const std::vector<float>& frameTimes)
{
    std::vector<float> times;
    std::vector<Eigen::Vector3f> scales;
    auto key = [&](float t, float s) {
        times.push_back(t);
        scales.push_back(Eigen::Vector3f::Constant(s));
    };
    if (track.firstFrame > 0) key(0.0f, 0.0f);
    key(frameTimes[track.firstFrame], 1.0f);
    if (track.lastFrame + 1 < int(frameTimes.size())) key(frameTimes[track.lastFrame + 1], 0.0f);
    if (times.size() > 1) addChannel(animation, node, "scale", packer.times(times), packer.vec3(scales), "STEP");
}

/// A node per fragment, placed at its first pose (hidden if it is born later), and the animation.
void addNodes(tinygltf::Model& model, BufferPacker& packer, const std::map<int64_t, Track>& tracks, const std::vector<float>& frameTimes,
              GltfExportReport& report)
{
    tinygltf::Animation animation;
    animation.name = "spall";
    tinygltf::Scene scene;
    for (const auto& [id, track] : tracks) {
        const int node = int(model.nodes.size());
        tinygltf::Node n;
        n.name = "fragment_" + std::to_string(id);
        if (track.mesh >= 0) n.mesh = track.mesh;
        const Pose& first = track.poses.front();
        n.translation = {first.position.x(), first.position.y(), first.position.z()};
        n.rotation = {first.rotation.x(), first.rotation.y(), first.rotation.z(), first.rotation.w()};
        if (track.firstFrame > 0) n.scale = {0.0, 0.0, 0.0};
        model.nodes.push_back(n);
        scene.nodes.push_back(node);
        report.keyframes += addPoseChannels(animation, packer, node, track.poses);
        addVisibilityChannel(animation, packer, node, track, frameTimes);
    }
    model.animations.push_back(animation);
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    report.nodes = int(tracks.size());
}

/// A node without a mesh per charge, `charge_<i>` where it was, its TNT mass in the node's extras
/// (`tnt_kg`): Blender imports it as an empty, the viewer draws a marker there.
void addChargeNodes(tinygltf::Model& model, const std::vector<Charge>& charges, GltfExportReport& report)
{
    for (size_t i = 0; i < charges.size(); ++i) {
        tinygltf::Node n;
        n.name = "charge_" + std::to_string(i);
        const Eigen::Vector3f p = toYUp(charges[i].positionM);
        n.translation = {p.x(), p.y(), p.z()};
        n.extras = tinygltf::Value(tinygltf::Value::Object{{"tnt_kg", tinygltf::Value(charges[i].tntKg)}});
        model.scenes.front().nodes.push_back(int(model.nodes.size()));
        model.nodes.push_back(n);
    }
    report.charges = int(charges.size());
}

/// A material's look by name: the run's scene's, else the preset's of that name, else a plain
/// grey one named "unnamed" (frames that do not name their material).
Material lookOf(const std::optional<Scene>& scene, const std::string& name)
{
    if (name.empty()) {
        Material plain;
        plain.name = "unnamed";
        return plain;
    }
    return scene ? scene->material(name) : findMaterialPreset(name);
}

openvdb::io::File openFrame(const std::string& path)
{
    openvdb::io::File file(path);
    try {
        file.open();
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read as .vdb: " + e.what());
    }
    return file;
}

/// A frame's time and the pose of every fragment in it, from the grids' metadata alone.
struct FramePoses {
    float timeS = 0.0f;
    std::vector<FragmentPose> fragments;
};

FramePoses readFramePoses(const std::string& path)
{
    openvdb::io::File file = openFrame(path);
    const auto fileMeta = file.getMetadata();
    const auto kind = fileMeta->getMetadata<openvdb::StringMetadata>("fragment_grids");
    if (!kind || kind->value() != "level_set")
        throw InputError(path + ": fragments are not level sets (output.fragment_grids); the glTF export meshes level sets: "
                                "run the scene again with \"fragment_grids\": \"level_set\"");
    FramePoses frame;
    frame.timeS = float(fileMeta->metaValue<double>("time_s"));
    const openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();
    for (const auto& grid : *grids)
        if (grid->getName().rfind("fragment_", 0) == 0) frame.fragments.push_back(poseOf(*grid, path));
    return frame;
}

/// The piece of fragment `pose.id` as frame `path` holds it.
PieceMesh readPiece(const std::string& path, const FragmentPose& pose, int64_t maxTriangles)
{
    openvdb::io::File file = openFrame(path);
    const std::string name = "fragment_" + std::to_string(pose.id), facesName = "fracture_faces_" + std::to_string(pose.id);
    const auto levelSet = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(name));
    if (!levelSet) throw InputError(path + ": " + name + " is not a float grid");
    const auto faces = file.hasGrid(facesName) ? openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(facesName)) : nullptr;
    return meshPiece(*levelSet, faces.get(), pose, maxTriangles);
}

}  // namespace

GltfExportReport exportGltf(const std::string& outputDirectory, const std::string& glbPath, const std::function<void(int, int)>& onFrame)
{
    initialiseOpenVdb();
    const std::vector<std::string> paths = listFramePaths(outputDirectory);
    // Reading thousands of grids' metadata per frame is most of the cost: frames in parallel.
    std::vector<FramePoses> frames(paths.size());
    std::mutex progress;
    int done = 0;
    forEachIndex(paths.size(), [&](size_t f) {
        frames[f] = readFramePoses(paths[f]);
        const std::lock_guard<std::mutex> lock(progress);
        if (onFrame) onFrame(++done, int(paths.size()));
    });
    std::vector<float> frameTimes;
    std::map<int64_t, Track> tracks;
    std::map<std::pair<uint64_t, std::string>, int> meshByKey;  // (mesh_key, material): a shape in each material
    std::vector<std::pair<size_t, FragmentPose>> firstOfEachMesh;  // (frame, fragment)
    for (size_t f = 0; f < frames.size(); ++f) {
        frameTimes.push_back(frames[f].timeS);
        for (const FragmentPose& pose : frames[f].fragments) {
            Track& track = tracks[pose.id];
            if (track.firstFrame < 0) {
                track.firstFrame = int(f);
                auto [found, isNew] = meshByKey.emplace(std::pair{pose.meshKey, pose.material}, int(firstOfEachMesh.size()));
                if (isNew) firstOfEachMesh.push_back({f, pose});
                track.mesh = found->second;
            }
            track.lastFrame = int(f);
            track.poses.push_back({frames[f].timeS, toYUp(pose.centreOfMassM), toYUp(pose.orientation)});
        }
    }
    if (tracks.empty()) throw InputError(outputDirectory + ": the frames hold no fragments");
    std::map<std::string, Material> looks;
    for (const auto& [frame, pose] : firstOfEachMesh) looks.emplace(pose.material, Material());
    const std::optional<Scene> scene = sceneOfRun(outputDirectory);
    for (auto& [name, material] : looks) material = lookOf(scene, name);
    const int64_t maxTriangles = scene ? scene->output.gltfMaxTrianglesPerPiece : OutputSettings().gltfMaxTrianglesPerPiece;
    std::vector<PieceMesh> pieces(firstOfEachMesh.size());
    forEachIndex(pieces.size(), [&](size_t i) { pieces[i] = readPiece(paths[firstOfEachMesh[i].first], firstOfEachMesh[i].second, maxTriangles); });

    GltfExportReport report;
    report.frames = int(paths.size());
    report.meshes = int(pieces.size());
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = std::string("spall ") + SPALL_VERSION;
    BufferPacker packer(model);
    addMeshes(model, packer, pieces, looks, report);
    addNodes(model, packer, tracks, frameTimes, report);
    addChargeNodes(model, scene ? scene->charges : std::vector<Charge>(), report);
    writeFileAtomically(glbPath, [&](std::ostream& out) {
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToStream(&model, out, false, true)) throw IoError(glbPath + ": tinygltf could not write the model");
    });
    report.bytes = std::filesystem::file_size(glbPath);
    return report;
}

}  // namespace spall
