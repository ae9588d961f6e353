// Contacts of bodies with the ground and the static boxes.
#pragma once

#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <vector>

namespace spall {

struct StaticContact {
    Eigen::Vector3d arm;     ///< from the body's centre of mass to the contact point (unit: m)
    Eigen::Vector3d normal;  ///< out of the collider
    double depth;            ///< negative: a gap within the speculative margin (unit: m)
    int collider;            ///< -1: the ground; else the box index
    double restitution, friction;
};

/// Corners of the body's boundary voxels inside the ground or a static box, or within a tenth
/// of a voxel of it, per collider and normal reduced to at most four spanning points.
std::vector<StaticContact> findStaticContacts(const Body& body, const WorldSettings& world);
/// Whether the body's bounding sphere comes within `reachM` of the ground or a static box.
bool withinReachOfStatics(const Body& body, const WorldSettings& world, double reachM);
/// The fastest a body's points close on the colliders of its contacts, along their normals, those
/// on the ground counted at `groundShare` of their speed (unit: m/s; 0 when none closes).
double fastestClosingSpeedMS(const Body& body, const std::vector<StaticContact>& contacts, double groundShare);

}  // namespace spall
