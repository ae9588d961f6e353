// The static world: the ground and the colliders, as the scene gives them (their keys' table is
// src/world/Settings.cpp) and as a simulation builds it once when it is set up (StaticWorld), for
// the loads (shadows), the lattices (supports, and what their particles may not pass into) and
// the contacts.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
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

/// How a collider holds the voxels of an object anchored to it (`"anchor": "supports"`):
/// clamped, by a bond of the material's own (a wall under a floor), or pinned, by one that
/// carries force but no moment (a pane in glazing beads: simply supported).
enum class SupportHold { Clamped, Pinned };
template <>
struct EnumNames<SupportHold> {
    static constexpr std::pair<SupportHold, const char*> kNames[] = {{SupportHold::Clamped, "clamped"}, {SupportHold::Pinned, "pinned"}};
};

/// The largest restitution and friction coefficient a scene may give (its keys' ranges).
constexpr double kMaxRestitution = 1.0;
constexpr double kMaxFriction = 100.0;

/// The ground as a scene gives it (the `ground` keys).
struct GroundPlane {
    bool enabled = true;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< pointing out of the ground (unit: 1, normalised)
    double offsetM = 0.0;       ///< plane: normal . x = offset (unit: m)
    double restitution = 0.2;   ///< (unit: fraction)
    double friction = 0.6;      ///< Coulomb coefficient (unit: 1)
    /// The ground as an elastic half-space under a lattice's particles (GroundCompliance); 0: as
    /// stiff as the body that strikes it (unit: Pa).
    double youngsModulusPa = 0.0;
    double poissonsRatio = 0.3;    ///< (unit: 1)
    double densityKgM3 = 1900.0;   ///< (unit: kg/m³)
};

/// What a compliant ground (GroundPlane::youngsModulusPa > 0) is under one face of side h of a
/// body pressing on it, as an elastic half-space: Lysmer and Richart's analog of a rigid footing
/// (J. Soil Mech. Found. Div. ASCE 92 (1966) 65), its static spring 4 G r / (1 - ν) (Boussinesq's
/// rigid punch) for the circle of the face's area (r = h / √π), and a dashpot of the half-space's
/// plane-wave impedance ρ c_p over the face, so that a body striking flat takes v Z₁ Z₂ / (Z₁ + Z₂)
/// (Kolsky, Stress Waves in Solids, 1963, ch. 4). Lattice::groundContact shares the spring over
/// the faces pressing at once.
struct GroundCompliance {
    double stiffnessNPerM = 0.0;
    double dashpotNSPerM = 0.0;
};
GroundCompliance groundCompliance(const GroundPlane& ground, double faceSideM);
/// The ground's plane-wave impedance ρ c_p (unit: Pa s/m); infinite for a rigid ground.
double groundImpedancePaSPerM(const GroundPlane& ground);

/// A static, unbreakable oriented box that bodies rest on and bounce off.
struct StaticBox {
    Eigen::Vector3d centreM = Eigen::Vector3d::Zero();                 ///< (unit: m)
    Eigen::Vector3d halfExtentM = Eigen::Vector3d::Constant(0.5);      ///< (unit: m)
    Eigen::Vector3d rotationDeg = Eigen::Vector3d::Zero();             ///< about x, then y, then z, world axes (unit: degrees)
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();   ///< from rotationDeg
    double restitution = 0.2;  ///< (unit: fraction)
    double friction = 0.6;     ///< Coulomb coefficient (unit: 1)
    SupportHold holds = SupportHold::Clamped;
    /// The pressure it bears on the voxels it holds, into them (the floors and roof a house
    /// wall carries under its head): a dead load in the deformable phase while they touch it,
    /// bonded or cracked apart (unit: Pa).
    double bearingPressurePa = 0.0;
};

/// The static world a simulation is set up with, built once (buildStaticWorld) and read by every
/// stage: the loads cast shadows with its boxes and clear a face resting on its ground only over
/// its other edges (UFC 3-340-02: S is the smaller of a wall's height and half-width); a lattice
/// bonds its anchored voxels to them, and its particles may not sink into them. Without a ground
/// unless one is set (a simulation's comes from its scene, on by default there).
struct StaticWorld {
    GroundPlane ground = GroundPlane{false};  ///< its normal of unit length
    /// The colliders' boxes (a window's frame, the floor over a wall).
    std::vector<ObstacleBox> boxes;
    /// Per box, 1 when it holds by a pin (a pane in glazing beads, simply supported), else 0
    /// (clamped, as if the box were more of the material); empty: every box clamps.
    std::vector<uint8_t> pinned;
    /// Per box, the Coulomb coefficient of what slides on it (unit: 1); empty: frictionless.
    std::vector<double> friction;
    /// Per box, the restitution of what bounces off it (unit: fraction); empty: none.
    std::vector<double> restitution;
    /// Per box, the pressure it bears on the voxels it holds (StaticBox) (unit: Pa); empty: none.
    std::vector<double> bearingPressurePa;
    /// What the bodies weigh by: a lattice enters the phase carrying its weight
    /// (Lattice::fromBody) (unit: m/s²); none unless set.
    Eigen::Vector3d gravityMS2 = Eigen::Vector3d::Zero();
};

/// The scene's ground (its normal made of unit length), colliders and gravity as the static world.
StaticWorld buildStaticWorld(const GroundPlane& ground, const std::vector<StaticBox>& colliders, const Eigen::Vector3d& gravityMS2);

// Keys and ranges (src/world/Settings.cpp).
template <>
const std::vector<Field<GroundPlane>>& fieldTable<GroundPlane>();
template <>
const std::vector<Field<StaticBox>>& fieldTable<StaticBox>();

}  // namespace spall
