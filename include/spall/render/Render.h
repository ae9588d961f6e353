// Preview pictures without a VFX package: exposed voxel faces of every fragment, flat-shaded,
// one colour per fragment, over a chequered ground, from a camera that frames the scene.
#pragma once

#include <spall/output/FrameWriter.h>
#include <spall/output/Png.h>
#include <spall/voxel/Body.h>

#include <openvdb/openvdb.h>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace spall {

/// A camera looking at `targetM` from `eyeM`, vertical field of view in degrees.
struct Camera {
    Eigen::Vector3d eyeM = Eigen::Vector3d(-6, -10, 4);
    Eigen::Vector3d targetM = Eigen::Vector3d::Zero();
    double verticalFovDeg = 40.0;
};

struct RenderSettings {
    int width = 960;
    int height = 540;
    double groundHeightM = 0.0;
    /// Where the charges were (unit: m): each is drawn as an orange disc, hidden where a
    /// fragment stands in front of it.
    std::vector<Eigen::Vector3d> chargesM;
};

/// The colour a charge is drawn in.
inline constexpr Rgb kChargeColour{255, 110, 0};

/// One frame's fragments as read from fragments.NNNN.vdb (the `fragment_*` grids).
struct FrameGrids {
    int frame = 0;
    double timeS = 0;
    std::vector<openvdb::FloatGrid::ConstPtr> fragments;
    std::vector<int64_t> ids;
};

/// Reads a frame file. Throws IoError naming the file when it is missing or not a spall frame.
FrameGrids readFrame(const std::string& path);

/// What the renderer draws: the active voxels of a grid (a file's FloatGrid or a body's link
/// grid) placed by a transform, in one colour per id.
struct FragmentRef {
    const openvdb::GridBase* grid = nullptr;
    openvdb::math::Transform::ConstPtr transform;
    int64_t id = 0;
};
std::vector<FragmentRef> fragmentsOf(const FrameGrids& frame);
std::vector<FragmentRef> fragmentsOf(const std::vector<Body>& bodies);

/// A camera from the front-left and above, as near as lets the given sets (all but the outermost
/// 1 % of their voxels on each side of each axis) fill 90 % of the picture's width or height.
Camera frameCamera(const std::vector<std::vector<FragmentRef>>& sets, const RenderSettings& settings);

/// Renders one set of fragments.
Image renderFragments(const std::vector<FragmentRef>& fragments, const Camera& camera, const RenderSettings& settings);

/// Tiles frames into a contact sheet with the time of each under it.
Image contactSheet(const std::vector<Image>& frames, const std::vector<double>& timesS, int columns);

/// Renders a contact sheet of up to `count` frames spread evenly over the run into `pngPath`,
/// from `camera` (default: one framing the first and last frames). Returns the number of frames
/// on the sheet.
int writeContactSheet(const std::string& outputDirectory, const std::string& pngPath, int count, const RenderSettings& settings,
                      const std::optional<Camera>& camera = std::nullopt);

}  // namespace spall
