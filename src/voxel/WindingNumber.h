// The generalised winding number of a triangle soup (Jacobson, Kavan and Sorkine-Hornung 2013,
// "Robust inside-outside segmentation using generalized winding numbers"): 1 inside a closed
// outward-wound surface, 0 outside, and a smooth value between where the surface has holes, so
// "inside" is w > 1/2 whatever the holes. Evaluated with the tree of Barill, Dickson, Schmidt,
// Levin and Jacobson 2018 ("Fast winding numbers for soups and clouds"): a cluster far from the
// query point counts as its dipole term, near triangles count exactly.
#pragma once

#include <spall/voxel/Body.h>
#include <spall/voxel/Voxelise.h>

#include <Eigen/Geometry>

#include <vector>

namespace spall {

class WindingNumberField {
public:
    explicit WindingNumberField(const TriangleMesh& mesh);

    /// Winding number at q (unit: turns; 1 inside an outward-wound closed surface).
    double at(const Eigen::Vector3d& q) const;

    /// True when some triangle meets the box.
    bool anyTriangleMeets(const Eigen::AlignedBox3d& box) const;

private:
    struct Node {
        Eigen::AlignedBox3d bounds;
        Eigen::Vector3d centreM;       ///< area-weighted centroid of the cluster
        Eigen::Vector3d areaNormalM2;  ///< sum of area times unit normal (the dipole moment)
        double radiusM = 0.0;          ///< farthest vertex from centreM
        int first = 0, count = 0;      ///< triangle range (leaves)
        int left = -1, right = -1;     ///< children (inner nodes)
    };
    struct Triangle {
        Eigen::Vector3d a, b, c;
    };

    int build(int first, int count);
    void summarise(Node& node) const;

    std::vector<Triangle> mTriangles;  ///< reordered so that every node owns a contiguous range
    std::vector<Node> mNodes;
};

/// Switches on the voxels of `solid` (an empty grid with the voxel size in its transform) whose
/// centres have a winding number above one half. Throws VoxeliseInterrupted when asked to stop.
void fillWindingNumberInterior(const TriangleMesh& mesh, LinkGrid& solid, const std::string& sourceName, Interrupter* interrupter);

}  // namespace spall
