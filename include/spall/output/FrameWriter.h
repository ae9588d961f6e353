// OUTDIR/fragments.NNNN.vdb: one frame of a run, every fragment where it is (docs/file-formats.md).
#pragma once

#include <spall/output/FragmentSurface.h>
#include <spall/scene/Scene.h>
#include <spall/voxel/Body.h>

#include <openvdb/openvdb.h>

#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace spall {

/// 1: fragment grids were fog (1 in each voxel); 2: level sets, fracture_faces_<id>, `v`.
inline constexpr int kFrameFormatVersion = 2;
/// Level-set narrow band each side of the surface (unit: samples).
inline constexpr float kLevelSetHalfWidthSamples = 3.0f;

struct FrameInfo {
    int frame = 0;  ///< the run's frame index, from 0 (the file's number adds output.first_frame)
    double timeS = 0;
    double frameRateHz = 0;  ///< written to the file's metadata when known (unit: 1/s)
};

/// Writes OUTDIR/fragments.NNNN.vdb: per body a FloatGrid `fragment_<id>` (a level set of its voxel
/// surface, or fog) whose transform places it in the world, with motion metadata; per body with
/// fracture surface a `fracture_faces_<id>` grid of which faces broke; and on request world-space
/// `density` and `v` grids. A body's trees are built once (bodies never change shape: a split makes
/// new bodies) and each tree starts at index (0,0,0) with the offset in its transform, so bodies of
/// the same shape — debris is full of single voxels — share one tree, which the file stores once
/// (OpenVDB instancing). With output.debris_level_set, a world-space level set `debris` holds
/// every piece's surface at once.
/// Bits of a `fracture_faces_<id>` voxel's value: 1 << face for each of its faces that broke
/// (voxel/LinkBits.h Face), and 1 << (kJointFaceBit + face) for those of them that run along a
/// masonry joint (the voxels either side lie in different units).
constexpr int kJointFaceBit = 6;

class FrameWriter {
public:
    /// `materials`: each body's material (Body::materialIndex), named in the fragments' metadata;
    /// a masonry material's broken faces across a joint are marked as such in fracture_faces.
    FrameWriter(std::string outputDirectory, const OutputSettings& settings, std::vector<Material> materials = {});
    /// Returns the path written.
    std::string write(const FrameInfo& info, const std::vector<Body>& bodies);
    /// How many level sets were made by updating a piece's earlier one near its new cracks
    /// (updatedVoxelSurfaceLevelSet) rather than whole, over the writer's frames.
    int64_t surfacesUpdated() const { return mSurfacesUpdated; }
    /// OUTDIR/fragments.NNNN.vdb, NNNN the frame's number (its index plus output.first_frame).
    static std::string framePath(const std::string& directory, int frameNumber);

private:
    struct FragmentTrees {
        openvdb::FloatTree::Ptr surface;
        openvdb::FloatTree::Ptr fractureFaces;  ///< null when the body has no fracture surface
        openvdb::Coord originIjk;               ///< the trees' (0,0,0) in the body's index space
        uint64_t meshKey = 0;                   ///< hash of voxels and fracture faces
        /// The grid they were made from: a body shown in pieces during the deformable phase
        /// (Simulation::showPieces) keeps a piece's id while the piece loses voxels to cracks.
        std::weak_ptr<const LinkGrid> madeFrom;
        int64_t parentId = kNoBodyId;
        /// The shape, kept where a piece that cracks further or breaks may be updated from it
        /// (null for small ones).
        VoxelShape shape;
    };
    /// Trees by content: equal content, one tree.
    struct Interned {
        openvdb::FloatTree::Ptr content;  ///< what was hashed and compared
        openvdb::FloatTree::Ptr derived;  ///< what is written (the content itself, or its level set)
    };
    const FragmentTrees& treesOf(const Body& body);
    /// The piece of the last frame that `body` is, or broke from, in the same voxel indices: the
    /// body itself, the one it was shown as part of (its parent), or a part of the same parent,
    /// one that holds the body's first voxel; null when none was kept.
    const FragmentTrees* earlierShapeOf(const Body& body) const;
    const Material* materialOf(const Body& body) const;
    SurfaceStyle surfaceStyle() const;
    static openvdb::FloatTree::Ptr intern(std::unordered_multimap<uint64_t, Interned>& pool, const openvdb::FloatTree::Ptr& content,
                                          uint64_t hash, const std::function<openvdb::FloatTree::Ptr()>& derive);
    openvdb::GridBase::Ptr fragmentGrid(const FrameInfo& info, const Body& body, const FragmentTrees& trees,
                                        const openvdb::math::Transform::Ptr& voxelMap) const;
    std::string mDirectory;
    OutputSettings mSettings;
    std::vector<Material> mMaterials;
    /// The trees of the bodies of the last frame written, and of the one being written.
    std::unordered_map<int64_t, FragmentTrees> mByBody, mShownNow;
    std::unordered_multimap<uint64_t, Interned> mShapes, mFractureFaces;
    int64_t mSurfacesUpdated = 0;
    /// Per body, its level set in the world frame as last resampled, with the surface and the
    /// pose it was made from: a body at rest is not resampled again (output.debris_level_set).
    struct WorldPiece {
        openvdb::FloatTree::ConstPtr surface;
        openvdb::math::Mat4d indexToWorld;
        openvdb::FloatGrid::ConstPtr inWorld;
    };
    std::unordered_map<int64_t, WorldPiece> mWorldPieces;
    openvdb::FloatGrid::Ptr debrisLevelSet(const std::vector<Body>& bodies, const std::vector<openvdb::FloatGrid::ConstPtr>& levelSets);
};

/// Paths of OUTDIR/fragments.NNNN.vdb in the order of their numbers. Throws InputError when the directory is missing or
/// holds no frames.
std::vector<std::string> listFramePaths(const std::string& outputDirectory);

/// World-space grids of voxel size h over all bodies: `density` (1 where a voxel centre of the
/// world grid falls inside some body voxel) and, if asked, `v` (the velocity of the material there,
/// v + ω × r; unit: m/s).
struct WorldGrids {
    openvdb::FloatGrid::Ptr density;
    openvdb::Vec3SGrid::Ptr velocity;
};
WorldGrids rasteriseBodies(const std::vector<Body>& bodies, double voxelSizeM, bool withVelocity);

/// A level set in its own (turned, moved) frame resampled into a world-aligned grid of samples
/// `sampleM` apart, as far apart as its own: the piece's band interpolated (trilinear) at the
/// world samples near it, which a rigid motion keeps a signed distance, then signed flood fill.
openvdb::FloatGrid::Ptr levelSetInWorld(const openvdb::FloatGrid& piece, double sampleM, float halfWidthSamples);
/// The union (CSG, the minimum) of world-aligned level sets of one sample spacing, copied: the
/// frame's `debris` grid.
openvdb::FloatGrid::Ptr levelSetUnion(const std::vector<openvdb::FloatGrid::ConstPtr>& pieces, double sampleM, float halfWidthSamples);

}  // namespace spall
