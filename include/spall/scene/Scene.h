// Scenes: JSON in SI units, read and written through each settings struct's field table
// (core/Fields.h). Every key is documented in docs/scene-format.md; unknown keys, wrong types and
// out-of-range values are errors naming the file, the key and the reason.
#pragma once

#include <spall/blast/Settings.h>
#include <spall/dynamics/Settings.h>
#include <spall/fracture/Material.h>
#include <spall/fracture/Settings.h>
#include <spall/lattice/Settings.h>
#include <spall/loads/Settings.h>
#include <spall/voxel/Settings.h>

#include <nlohmann/json_fwd.hpp>

#include <optional>
#include <string>
#include <vector>

namespace spall {

/// What an object's voxels are bonded to: nothing, the ground, or the ground and the colliders
/// (a pane in its frame, a wall under a floor).
enum class AnchorMode { None, Ground, Supports };
template <>
struct EnumNames<AnchorMode> {
    static constexpr std::pair<AnchorMode, const char*> kNames[] = {
        {AnchorMode::None, "none"}, {AnchorMode::Ground, "ground"}, {AnchorMode::Supports, "supports"}};
};

/// The length unit a mesh file's coordinates are in (glTF's is the metre; CAD and modelling
/// tools often write millimetres, centimetres or inches).
enum class MeshUnit { Metre, Centimetre, Millimetre, Inch, Foot };
template <>
struct EnumNames<MeshUnit> {
    static constexpr std::pair<MeshUnit, const char*> kNames[] = {
        {MeshUnit::Metre, "m"}, {MeshUnit::Centimetre, "cm"}, {MeshUnit::Millimetre, "mm"}, {MeshUnit::Inch, "in"}, {MeshUnit::Foot, "ft"}};
};

struct ObjectSpec {
    std::string name;
    std::string meshPath;                 ///< resolved against the scene file; empty for primitives
    std::optional<Primitive> primitive;   ///< read and written by hand: its keys depend on its shape
    Eigen::Vector3d positionM = Eigen::Vector3d::Zero();     ///< where the object's local origin goes (unit: m)
    Eigen::Vector3d rotationDeg = Eigen::Vector3d::Zero();   ///< about x, then y, then z, world axes (unit: degrees)
    /// Its motion at the start (a brick thrown at a window): its centre of mass's velocity and
    /// its spin about it; none for an anchored object (unit: m/s, rad/s).
    Eigen::Vector3d linearVelocityMS = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularVelocityRadS = Eigen::Vector3d::Zero();
    std::string material = "brick-masonry";
    AnchorMode anchor = AnchorMode::None;
    InsideTest inside = InsideTest::Auto;  ///< meshes only (docs/voxelisation.md)
    double shellThicknessM = 0.0;          ///< meshes only: > 0 makes a shell of the surface (unit: m)
    MeshUnit meshUnit = MeshUnit::Metre;   ///< meshes only: what the file's coordinates are in
    /// Every length of the object times this, about its local origin (mesh or primitive) (unit: 1).
    double scale = 1.0;
};

/// What one unit of an object's own coordinates is in the world: its mesh unit times its scale
/// (unit: m).
double objectUnitM(const ObjectSpec& spec);

/// What each fragment_<id> grid in a frame holds (docs/file-formats.md).
enum class FragmentGrids {
    LevelSet,  ///< narrow-band signed distance to the fragment's voxel surface: meshes into a solid
    Fog,       ///< 1 in each voxel (format 1, for readers that relied on it)
};
template <>
struct EnumNames<FragmentGrids> {
    static constexpr std::pair<FragmentGrids, const char*> kNames[] = {{FragmentGrids::LevelSet, "level_set"}, {FragmentGrids::Fog, "fog"}};
};

struct OutputSettings {
    bool vdb = true;           ///< fragments.NNNN.vdb per frame
    FragmentGrids fragmentGrids = FragmentGrids::LevelSet;
    /// Level-set samples per voxel edge, one on each voxel face: from 2 up, volume-to-mesh gives
    /// back the voxel surface exactly (at 1 a concave corner, all of whose samples lie on the
    /// surface, would fill in); more samples only matter for smoothing (unit: 1).
    int levelSetSubdivisions = 3;
    /// Mean-curvature flow iterations of each fragment's fracture surface, the volume restored
    /// after (0: the voxel staircase). The object's own surface stays as modelled
    /// (docs/file-formats.md) (unit: 1).
    int fractureSmoothingSteps = 4;
    /// Fracture faces moved in and out by smooth noise, at most this fraction of a voxel edge, so
    /// breaks look rough while the object's own surface stays as modelled (0: flat; at most 0.2,
    /// so every voxel's centre stays on its side of the surface) (unit: voxel edges).
    double fractureRoughnessVoxels = 0.0;
    /// Triangles a piece of the glTF may have: a piece over it is meshed adaptively (OpenVDB's
    /// adaptivity, raised until it fits or reaches 1), which merges flat regions (0: every piece
    /// exact) (unit: triangles).
    int64_t gltfMaxTrianglesPerPiece = 1000;
    bool densityGrid = true;   ///< world-space `density` grid in each frame
    /// World-space `debris` level set in each frame: every piece's surface in one grid, for a
    /// single Volume to Mesh in Blender (the per-fragment grids stay beside it). Costs a
    /// resampling of each piece every frame, so only when asked.
    bool debrisLevelSet = false;
    /// The number of the run's first frame, in the file names and the frames' metadata: a
    /// scene's time t is frame first_frame + t × frame_rate_hz (1001 is the film convention)
    /// (unit: frames).
    int firstFrame = 0;
    bool velocityGrid = false; ///< world-space `v` grid (velocity of the material there, m/s) beside `density`
    bool history = true;       ///< history.h5
    /// OUTDIR/checkpoint.spall, for `spall run --resume`: after the first frame that ends this
    /// long (wall-clock) after the last checkpoint or the start, and when a run is stopped on
    /// request (0: never). Bounds the work an interruption loses without paying for a
    /// checkpoint every frame (unit: s).
    double checkpointEveryS = 30.0;
};

struct Scene {
    std::string sourceName = "<built-in default>";
    double voxelSizeM = 0.05;   ///< (unit: m)
    double durationS = 4.0;     ///< (unit: s)
    double frameRateHz = 24.0;  ///< (unit: 1/s)
    uint64_t seed = 1;          ///< every random choice derives from it (the one copy: passed to what draws)
    int64_t maxVoxels = 20'000'000;  ///< voxelising more is an error (unit: voxels)
    WorldSettings world;
    SleepSettings sleep;
    BlastSettings blast;
    LoadSettings loads;
    FractureSettings fracture;
    LatticeSettings lattice;
    TimeStepSettings timeStep;
    CollisionSettings collisions;
    std::vector<Material> materials;  ///< presets plus the scene's own
    std::vector<ObjectSpec> objects;
    std::vector<Charge> charges;
    OutputSettings output;

    int frameCount() const { return static_cast<int>(std::floor(durationS * frameRateHz + 1e-9)) + 1; }
    const Material& material(const std::string& name) const;
};

// Keys and ranges (src/scene/Scene.cpp). A scene's own table holds its top-level numbers; its
// settings structs, lists and materials have tables of their own.
template <>
const std::vector<Field<ObjectSpec>>& fieldTable<ObjectSpec>();
template <>
const std::vector<Field<OutputSettings>>& fieldTable<OutputSettings>();
template <>
const std::vector<Field<Scene>>& fieldTable<Scene>();

/// Rotation about the world x, then y, then z axes (degrees), as scenes give it.
Eigen::Quaterniond rotationFromDegrees(const Eigen::Vector3d& degrees);

/// The built-in default scene (also assets/scenes/default.json): a one-brick wall (two leaves of
/// bricks in mortar, resolved at 2.5 cm) breached by 0.4 kg of TNT 0.4 m in front, fracture from
/// stress.
const char* defaultSceneJson();

/// The default scene before fracture from stress (also assets/scenes/brick-wall-yield-limit.json):
/// a 4 m wall at 0.1 m voxels, 20 kg at 4 m, the paper's yield-limit rule; `spall bench accuracy`
/// studies its tolerances.
const char* paperWallSceneJson();

/// Parses scene JSON. `sourceName` names the file in errors; relative mesh paths resolve
/// against `baseDirectory`.
Scene parseScene(const std::string& text, const std::string& sourceName, const std::string& baseDirectory);

/// Reads and parses a scene file.
Scene loadScene(const std::string& path);

/// The scene with every default filled in, in the same format (parses back to the same scene;
/// a checkpoint stores it so).
nlohmann::json sceneToJson(const Scene& scene);

}  // namespace spall
