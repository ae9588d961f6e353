// Narrow phase (paper section 4.2): voxel against voxel between bodies. Three methods find the
// same voxel pairs: the paper's pairwise test of every boundary voxel against every other, its
// buckets (a spatial hash of boundary voxels), and spall's own, which moves each boundary voxel
// of one body into the other body's index space and looks it up in that body's tree (O(1) per
// voxel). Voxels meet as cubes (a separating-axis test); pairs a tenth of a voxel apart are kept
// as speculative contacts. docs/architecture.md, "Collisions", says why.
#pragma once

#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <cstdint>
#include <vector>

namespace spall {

/// One touching pair of voxels, world frame.
struct VoxelContact {
    Eigen::Vector3d pointM;   ///< midpoint of the two centres (unit: m)
    Eigen::Vector3d normal;   ///< unit, from body b's voxel to body a's
    /// The cubes' overlap along the normal, negative for a gap (contacts are found a tenth of a
    /// voxel early so that resting contacts do not flicker on and off) (unit: m).
    double depthM;
};

/// The contacts of a pair of bodies reduced to at most four points sharing one normal.
struct ContactManifold {
    int a = -1, b = -1;  ///< body indices, a < b
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< from b to a
    std::vector<VoxelContact> points;
    double maxDepthM = 0;        ///< (unit: m)
    int64_t voxelContacts = 0;  ///< voxel pairs found before reduction
};

/// Contacts between bodies by `method` (None gives nothing). Manifolds come sorted by pair; the
/// result does not depend on the thread count.
std::vector<ContactManifold> findBodyContacts(const std::vector<Body>& bodies, CollisionMethod method);

/// Reduces a pair's voxel contacts to a manifold: the normal is the depth-weighted mean of the
/// voxel normals (their tangential parts cancel across a flat contact, which is what keeps
/// stacked debris from sliding), the points four that span the patch (spanningPoints), its
/// depth the deepest pair's.
ContactManifold reduceManifold(int a, int b, const std::vector<VoxelContact>& contacts, double voxelSizeM);

/// At most four of the contacts: the patch's extreme along a fixed tangent (a corner, which
/// stays put while depths change), the farthest from it, and the farthest from their line on
/// each side (indices into `contacts`).
std::vector<size_t> spanningPoints(const std::vector<VoxelContact>& contacts, const Eigen::Vector3d& normal);

}  // namespace spall
