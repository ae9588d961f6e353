// Inside the narrow phase: what every method shares (the reach, the cube-cube contact) and the
// paper's two baselines, which NarrowPhase.cpp dispatches to.
#pragma once

#include <spall/dynamics/NarrowPhase.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace spall::narrow {

/// Contacts are found this far (in voxels) before they touch and solved speculatively (the
/// approach may only close the gap), so a resting contact does not flicker on and off.
constexpr double kContactMarginVoxels = 0.1;
/// Voxel pairs closer than this (in voxels) are tested as cubes. The paper's one voxel misses
/// turned cubes touching corner to edge, which then sink into each other unseen; sqrt(2) plus
/// the margin catches every pair turned about one axis, and what it misses across a body
/// diagonal overlaps by under a quarter voxel.
constexpr double kReach = 1.4143 + kContactMarginVoxels;

/// The separating axes of a voxel of body a against one of body b (rotations ra, rb) and the
/// cubes' projected radius along each: the six face axes, then the edge-edge axes that are not
/// parallel to a face axis. Every voxel pair of a body pair shares them, so they are built once
/// per pair.
struct CubePairAxes {
    std::array<Eigen::Vector3d, 15> axis;
    std::array<double, 15> radius;
    int count = 0;

    CubePairAxes(const Eigen::Matrix3d& ra, const Eigen::Matrix3d& rb, double h)
    {
        // c(i, j) = a's axis i . b's axis j; every projected radius follows from it.
        const Eigen::Matrix3d c = ra.transpose() * rb;
        const Eigen::Matrix3d absC = c.cwiseAbs();
        const double half = 0.5 * h;
        for (int i = 0; i < 3; ++i) add(ra.col(i), half * (1.0 + absC.row(i).sum()));
        for (int j = 0; j < 3; ++j) add(rb.col(j), half * (1.0 + absC.col(j).sum()));
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double sine2 = 1.0 - c(i, j) * c(i, j);
                if (sine2 < 1e-6) continue;  // parallel edges: a face axis covers it
                const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
                const double norm = std::sqrt(sine2);
                add(ra.col(i).cross(rb.col(j)) / norm, half * (absC(i1, j) + absC(i2, j) + absC(i, j1) + absC(i, j2)) / norm);
            }
    }

private:
    void add(const Eigen::Vector3d& unitAxis, double r)
    {
        axis[count] = unitAxis;
        radius[count] = r;
        ++count;
    }
};

/// Contact of a voxel of body a with one of body b, given the world vector from b's voxel centre
/// to a's. The voxels are cubes: the normal is the axis along which they overlap least
/// (separating-axis test), the depth that overlap (negative: a gap). The paper's line between
/// centres tilts whenever two faces meet offset by a fraction of a voxel, and tilted normals make
/// resting debris slide and rattle. Returns false when the cubes are separated by more than the
/// speculative margin.
inline bool makeVoxelContact(const CubePairAxes& axes, double h, const Eigen::Vector3d& centreA, const Eigen::Vector3d& bToA,
                      VoxelContact& out)
{
    const double separated = -kContactMarginVoxels * h;
    double best = std::numeric_limits<double>::infinity();
    int bestAxis = 0;
    double bestAlong = 0;
    for (int k = 0; k < axes.count; ++k) {
        const double along = axes.axis[k].dot(bToA);
        const double overlap = axes.radius[k] - std::abs(along);
        if (overlap < best) {
            best = overlap;
            bestAxis = k;
            bestAlong = along;
            if (best <= separated) return false;
        }
    }
    const Eigen::Vector3d normal = bestAlong >= 0 ? axes.axis[bestAxis] : Eigen::Vector3d(-axes.axis[bestAxis]);
    out = {centreA - 0.5 * bToA, normal, best};
    return true;
}

/// The manifolds that hold a contact (voxels within reach can still be apart as cubes).
std::vector<ContactManifold> withoutEmpty(std::vector<ContactManifold> manifolds);

/// The paper's first scheme: every boundary voxel against every boundary voxel of other bodies.
std::vector<ContactManifold> pairwiseContacts(const std::vector<Body>& bodies);

/// The paper's second scheme: boundary voxels sorted into buckets as wide as the contact reach;
/// each voxel is tested against the voxels of its own and the 26 adjacent buckets.
std::vector<ContactManifold> bucketContacts(const std::vector<Body>& bodies);

}  // namespace spall::narrow
