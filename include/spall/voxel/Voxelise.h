// Solid voxelisation of meshes (through assimp and OpenVDB's mesh-to-volume) and of primitives.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Error.h>
#include <spall/voxel/Body.h>
#include <spall/voxel/Settings.h>

#include <Eigen/Geometry>

#include <stdexcept>
#include <string>
#include <vector>

namespace spall {

/// How a mesh's inside is found. Auto takes the level set for watertight meshes (exact and
/// fastest) and the winding number for meshes with holes.
struct VoxeliseResult {
    LinkGrid::Ptr grid;  ///< solid voxels, all links intact, index space at voxel size
    int64_t voxelCount = 0;
    /// Object-local position of index (0,0,0): local = index * h + offset (unit: m). Boxes use 0 or
    /// h/2 per axis so that their voxel cubes tile the box exactly; meshes about h/2, so that their
    /// cubes tile the object's frame from its origin (voxeliseMesh).
    Eigen::Vector3d localOffsetM = Eigen::Vector3d::Zero();
    /// Volume the mesh encloses, for comparison with the voxels' (unit: m^3; 0 for primitives).
    double enclosedVolumeM3 = 0.0;
    /// Repairs and observations a user should know about (open edges, dropped points, ...).
    std::vector<std::string> notes;
};

/// A triangle mesh in metres.
struct TriangleMesh {
    std::vector<Eigen::Vector3f> positionsM;
    std::vector<Eigen::Vector3i> triangles;
};

/// Loads every triangle of every mesh in a file assimp reads (OBJ, STL, PLY, OFF, glTF, ...).
/// Throws InputError naming the file and the reason.
TriangleMesh loadMesh(const std::string& path, std::vector<std::string>* notes = nullptr);

/// Thrown when an interrupter stopped the work (Ctrl-C, SIGTERM): nothing was produced.
class VoxeliseInterrupted : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Solid interior of a mesh: voxel centres inside the surface (see InsideTest). Throws InputError
/// if the interior is not well defined or the fill lost most of the enclosed volume,
/// VoxeliseInterrupted when `interrupter` asks to stop.
VoxeliseResult voxeliseMesh(const TriangleMesh& mesh, const VoxeliseSettings& settings,
                            const std::string& sourceName, Interrupter* interrupter = nullptr);

VoxeliseResult voxelisePrimitive(const Primitive& primitive, const VoxeliseSettings& settings);

/// Voxels in the object's bounding box at voxel size h (unit: m): an upper bound on its voxel
/// count, known before anything is allocated.
double boundingBoxVoxels(const TriangleMesh& mesh, double h);
double boundingBoxVoxels(const Primitive& primitive, double h);

/// Half the extent of a primitive's bounding box along its axes (unit: m).
Eigen::Vector3d primitiveHalfExtentM(const Primitive& primitive);

}  // namespace spall
