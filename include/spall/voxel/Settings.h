// Settings of voxelising: how a mesh's inside is found, the voxel size and budget, and the
// primitives a scene can name instead of a mesh. Plain structs with a unit on every field; apart
// from voxel/Voxelise.h so that a scene's settings need not bring in OpenVDB.
#pragma once

#include <spall/core/EnumNames.h>

#include <Eigen/Core>

#include <cstdint>

namespace spall {

enum class InsideTest { Auto, LevelSet, WindingNumber };
template <>
struct EnumNames<InsideTest> {
    static constexpr std::pair<InsideTest, const char*> kNames[] = {
        {InsideTest::Auto, "auto"}, {InsideTest::LevelSet, "level-set"}, {InsideTest::WindingNumber, "winding-number"}};
};

struct VoxeliseSettings {
    double voxelSizeM = 0.05;          ///< edge of a voxel (unit: m)
    int64_t maxVoxels = 200'000'000;   ///< refuse larger results (unit: voxels)
    InsideTest insideTest = InsideTest::Auto;
    /// Above 0: instead of its inside, the voxels whose centres lie within half this of the
    /// surface, for surfaces with no inside (a sheet, a terrain patch) (unit: m).
    double shellThicknessM = 0.0;
};

enum class PrimitiveShape { Box, Sphere, Cylinder };
template <>
struct EnumNames<PrimitiveShape> {
    static constexpr std::pair<PrimitiveShape, const char*> kNames[] = {
        {PrimitiveShape::Box, "box"}, {PrimitiveShape::Sphere, "sphere"}, {PrimitiveShape::Cylinder, "cylinder"}};
};

/// A primitive centred on the object's origin: a box of full extents sizeM, a sphere of radius
/// sizeM.x(), or a cylinder along z of radius sizeM.x() and height sizeM.z().
struct Primitive {
    PrimitiveShape shape = PrimitiveShape::Box;
    Eigen::Vector3d sizeM = Eigen::Vector3d::Ones();
};

}  // namespace spall
