#include <spall/world/StaticWorld.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spall {

GroundCompliance groundCompliance(const GroundPlane& ground, double faceSideM)
{
    if (ground.youngsModulusPa <= 0.0) return {};
    const double nu = ground.poissonsRatio, shearPa = ground.youngsModulusPa / (2.0 * (1.0 + nu));
    const double radiusM = faceSideM / std::sqrt(M_PI);
    return {4.0 * shearPa * radiusM / (1.0 - nu), groundImpedancePaSPerM(ground) * faceSideM * faceSideM};
}

double groundImpedancePaSPerM(const GroundPlane& ground)
{
    if (ground.youngsModulusPa <= 0.0) return std::numeric_limits<double>::infinity();
    const double nu = ground.poissonsRatio;
    // The constrained (P-wave) modulus E (1 - ν) / ((1 + ν)(1 - 2ν)); ρ c_p = sqrt(ρ M).
    const double constrainedPa = ground.youngsModulusPa * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    return std::sqrt(ground.densityKgM3 * constrainedPa);
}

std::array<Eigen::Vector3d, 8> cornersOf(const ObstacleBox& box)
{
    const Eigen::Matrix3d rot = box.orientation.toRotationMatrix();
    std::array<Eigen::Vector3d, 8> corners;
    for (int c = 0; c < 8; ++c)
        corners[c] = box.centreM + rot * Eigen::Vector3d((c & 1 ? 1 : -1) * box.halfExtentM.x(), (c & 2 ? 1 : -1) * box.halfExtentM.y(),
                                                         (c & 4 ? 1 : -1) * box.halfExtentM.z());
    return corners;
}

double depthInsideM(const ObstacleBox& box, const Eigen::Vector3d& pointM)
{
    // Per axis, how far the point lies beyond the face on its side (negative: inside).
    const Eigen::Vector3d beyond = (box.orientation.inverse() * (pointM - box.centreM)).cwiseAbs() - box.halfExtentM;
    const double outsideM = beyond.cwiseMax(0.0).norm();
    return outsideM > 0.0 ? -outsideM : -beyond.maxCoeff();
}

bool segmentMeetsBox(const Eigen::Vector3d& aM, const Eigen::Vector3d& bM, const ObstacleBox& box)
{
    const Eigen::Matrix3d toBox = box.orientation.toRotationMatrix().transpose();
    const Eigen::Vector3d p = toBox * (aM - box.centreM), d = toBox * (bM - aM);
    double enter = 0.0, leave = 1.0;
    for (int axis = 0; axis < 3; ++axis) {
        const double lo = -box.halfExtentM[axis], hi = box.halfExtentM[axis];
        if (std::abs(d[axis]) < 1e-15) {
            if (p[axis] < lo || p[axis] > hi) return false;
            continue;
        }
        double t0 = (lo - p[axis]) / d[axis], t1 = (hi - p[axis]) / d[axis];
        if (t0 > t1) std::swap(t0, t1);
        enter = std::max(enter, t0);
        leave = std::min(leave, t1);
        if (enter > leave) return false;
    }
    return true;
}

bool boxesMeet(const ObstacleBox& a, const ObstacleBox& b, double gapM)
{
    const Eigen::Matrix3d ra = a.orientation.toRotationMatrix(), rb = b.orientation.toRotationMatrix();
    const Eigen::Vector3d between = b.centreM - a.centreM;
    // Each box's extent along a unit axis is the sum of its half extents times |cos| to it.
    const auto separates = [&](const Eigen::Vector3d& axis) {
        const double length = axis.norm();
        if (length < 1e-12) return false;  // parallel edges: covered by the face normals
        const Eigen::Vector3d unit = axis / length;
        const double reachA = (ra.transpose() * unit).cwiseAbs().dot(a.halfExtentM);
        const double reachB = (rb.transpose() * unit).cwiseAbs().dot(b.halfExtentM);
        return std::abs(between.dot(unit)) > reachA + reachB + gapM;
    };
    for (int i = 0; i < 3; ++i)
        if (separates(ra.col(i)) || separates(rb.col(i))) return false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (separates(ra.col(i).cross(rb.col(j)))) return false;
    return true;
}

StaticWorld buildStaticWorld(const GroundPlane& ground, const std::vector<StaticBox>& colliders, const Eigen::Vector3d& gravityMS2)
{
    StaticWorld world;
    world.gravityMS2 = gravityMS2;
    world.ground = ground;
    world.ground.normal = ground.normal.normalized();
    for (const StaticBox& box : colliders) {
        world.boxes.push_back({box.centreM, box.halfExtentM, box.orientation});
        world.pinned.push_back(box.holds == SupportHold::Pinned ? 1 : 0);
        world.friction.push_back(box.friction);
        world.restitution.push_back(box.restitution);
        world.bearingPressurePa.push_back(box.bearingPressurePa);
    }
    return world;
}

}  // namespace spall
