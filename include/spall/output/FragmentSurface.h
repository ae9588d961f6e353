// A fragment's surface as a narrow-band level set: the solid a reader meshes (Houdini's Convert
// VDB, Blender's Volume to Mesh, spall's glTF export all use OpenVDB's volume-to-mesh).
#pragma once

#include <openvdb/openvdb.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace spall {

/// One exposed voxel face, in the shape's own voxel indices.
struct VoxelFace {
    openvdb::Coord voxel;
    int face;               ///< LinkBits.h's Face
    bool fracture = false;  ///< a link broke here (not the object's own surface)
};

/// How a fragment's level set is drawn from its voxels.
struct SurfaceStyle {
    /// Samples per voxel edge, one on every voxel face (from 2 up).
    int subdivisions = 3;
    /// Mean-curvature flow steps of the fracture surface, the volume restored after (0: the
    /// exact voxel surface).
    int smoothingSteps = 0;
    /// Largest displacement of fracture faces by smooth value noise, as a fraction of the voxel
    /// edge (0: flat; below 0.25 each voxel's centre stays on its side, which voxelsOfLevelSet needs).
    double fractureRoughness = 0.0;
    float halfWidthSamples = 3.0f;
};

/// Signed distance (unit: m) to the boundary of a union of voxel cubes (`voxels`, 1 in each),
/// given by its exposed faces, in a narrow band of `halfWidthSamples` samples each side: exact, the
/// least distance to the faces whose band reaches each sample, signed by the voxel holding it.
/// Samples lie `subdivisions` per voxel
/// edge with one on every voxel face (sample u at voxel index u / subdivisions - 0.5), so the zero
/// surface passes through the faces' corners and volume-to-mesh rebuilds the voxel surface exactly
/// (no bevelled edges). Smoothing steps then round the fracture surface's staircase, keeping the
/// volume and the object's own surface; fracture
/// roughness then moves fracture faces in and out by value noise that fades to nothing within
/// half a voxel of the object's own surface, which stays as it was (docs/file-formats.md).
openvdb::FloatTree::Ptr voxelSurfaceLevelSet(const std::vector<VoxelFace>& faces, const openvdb::FloatTree& voxels, double voxelSizeM,
                                             const SurfaceStyle& style);

/// A shape as the frames keep it: its voxels (1 in each) and, per voxel, the bits of its broken
/// faces (FrameWriter's fracture_faces), in the shape's own voxel indices.
struct VoxelShape {
    openvdb::FloatTree::Ptr voxels, brokenFaceBits;
};
/// A shape with the level set voxelSurfaceLevelSet made of it.
struct VoxelShapeSurface {
    VoxelShape shape;
    openvdb::FloatTree::Ptr surface;
};
/// The level set voxelSurfaceLevelSet makes of `now` (`exposedFaceCount` faces), made from
/// `previous`, an earlier shape in the same voxel indices and style with its level set: the leaves
/// within reach of the voxels where the shapes or their broken faces differ are remade from the
/// voxels around them (closed by faces where they meet voxels further out), and the others copied.
/// Unsmoothed and unroughened it is the whole shape's level set to the bit; smoothed, its volume
/// is restored over the remade region rather than the whole (docs/file-formats.md). A cracking
/// wall's frame pays for its new cracks, not for its whole surface. Null when the remade region
/// holds over half the shape's faces: then a whole level set costs no more.
openvdb::FloatTree::Ptr updatedVoxelSurfaceLevelSet(const VoxelShapeSurface& previous, const VoxelShape& now, size_t exposedFaceCount,
                                                    double voxelSizeM, const SurfaceStyle& style);

/// The level set's index-to-world map, from its voxels' index-to-world map.
openvdb::math::Transform::Ptr levelSetTransform(const openvdb::math::Transform& voxelIndexToWorld, int subdivisions);

/// A level set's zero surface as OpenVDB's volume-to-mesh makes it (adaptivity 0), in the world,
/// its quads split in two.
struct SurfaceMesh {
    std::vector<Eigen::Vector3d> pointsM;
    std::vector<std::array<uint32_t, 3>> triangles;
    /// By the divergence theorem: positive when the triangles wind outward (unit: m^3).
    double signedVolumeM3() const;
    double areaM2() const;
};
/// The level set's zero crossing meshed by OpenVDB's volume-to-mesh, at `adaptivity` (0 exact,
/// up to 1: flat regions merged into larger polygons).
SurfaceMesh meshLevelSet(const openvdb::FloatGrid& levelSet, double adaptivity = 0.0);

/// The voxels' index-to-world map, from the level set's (the inverse of levelSetTransform).
openvdb::math::Transform::Ptr voxelTransformOf(const openvdb::math::Transform& levelSetTransform, int subdivisions);

/// The voxels of a level set written by voxelSurfaceLevelSet: those whose centres lie inside, as
/// fog (1 in each) in the voxels' own index space. Exact for an unsmoothed level set; smoothed,
/// the voxels whose centres the smoothed surface still holds.
openvdb::FloatGrid::Ptr voxelsOfLevelSet(const openvdb::FloatGrid& levelSet, int subdivisions);

}  // namespace spall
