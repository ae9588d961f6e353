// The static world as the loads stage needs it: the ground and the boxes that cast shadows.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <vector>

namespace spall {

/// A box that casts a blast shadow: a scene's static collider, or a body's oriented bounds.
struct ObstacleBox {
    Eigen::Vector3d centreM = Eigen::Vector3d::Zero();
    Eigen::Vector3d halfExtentM = Eigen::Vector3d::Ones();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< box to world
};

/// The box's eight corners in the world.
std::array<Eigen::Vector3d, 8> cornersOf(const ObstacleBox& box);

/// How deep a point lies inside the box: its distance to the box's surface, positive inside and
/// negative outside (unit: m).
double depthInsideM(const ObstacleBox& box, const Eigen::Vector3d& pointM);

/// True when the segment from a to b meets the box (slab test in the box's frame).
bool segmentMeetsBox(const Eigen::Vector3d& aM, const Eigen::Vector3d& bM, const ObstacleBox& box);

/// True when the two boxes overlap or lie within `gapM` of each other along every separating
/// axis (the separating axis test for oriented boxes: their 3 + 3 face normals and 9 edge
/// cross products; Gottschalk, Lin and Manocha 1996, "OBBTree").
bool boxesMeet(const ObstacleBox& a, const ObstacleBox& b, double gapM);

/// The ground plane: a face region resting on it clears only over its other edges (UFC
/// 3-340-02: S is the smaller of a wall's height and half-width), and no wave goes under it.
struct LoadGround {
    bool enabled = false;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, pointing up
    double heightM = 0.0;                               ///< offset along the normal (unit: m)
};

struct LoadGeometry {
    LoadGround ground;
    std::vector<ObstacleBox> obstacles;
};

}  // namespace spall
