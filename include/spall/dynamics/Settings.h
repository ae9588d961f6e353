// Settings of the rigid-body stage: the world bodies move in, the time step, collisions, sleep.
// Plain structs with defaults and a unit on every field; src/dynamics/Settings.cpp holds their
// tables (the ground's and the colliders', src/world/Settings.cpp).
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>
#include <spall/world/StaticWorld.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace spall {

enum class Integrator { ExplicitEuler, SemiImplicitEuler, RungeKutta4 };
template <>
struct EnumNames<Integrator> {
    static constexpr std::pair<Integrator, const char*> kNames[] = {
        {Integrator::ExplicitEuler, "explicit-euler"}, {Integrator::SemiImplicitEuler, "semi-implicit-euler"}, {Integrator::RungeKutta4, "rk4"}};
};

/// Drag of the air on bodies in flight (dynamics/AirDrag.h).
enum class AirDrag { None, HaiderLevenspiel };
template <>
struct EnumNames<AirDrag> {
    static constexpr std::pair<AirDrag, const char*> kNames[] = {{AirDrag::None, "none"}, {AirDrag::HaiderLevenspiel, "haider-levenspiel"}};
};

struct WorldSettings {
    Eigen::Vector3d gravityMS2 = Eigen::Vector3d(0, 0, -9.81);  ///< (unit: m/s^2)
    /// The still air's drag on every rigid body in flight; the blast wind is the loads stage's.
    AirDrag airDrag = AirDrag::HaiderLevenspiel;
    double linearDragPerS = 0.0;   ///< an artist's extra damping, F = -k m v (unit: 1/s)
    double angularDragPerS = 0.0;  ///< tau = -k I w (unit: 1/s)
    GroundPlane ground;
    std::vector<StaticBox> colliders;
};

struct SleepSettings {
    bool enabled = true;
    /// Speed of the body's fastest voxel (linear plus angular times radius) below which it
    /// rests: one number for large and small bodies alike (unit: m/s).
    double speedMS = 0.05;
    double timeS = 0.5;  ///< resting this long puts it to sleep (unit: s)
};

/// Adaptive time step (docs/architecture.md, "Time step").
struct TimeStepSettings {
    Integrator integrator = Integrator::SemiImplicitEuler;
    double maxTimeStepS = 1.0 / 240.0;  ///< in free flight (unit: s)
    double minTimeStepS = 1e-7;         ///< floor, so a run always progresses (unit: s)
    double frontFraction = 0.5;         ///< shock front moves at most this many voxels (lattice particles, lattice.particle_voxels > 1) per step (unit: voxels)
    double pulseFraction = 1.0 / 32.0;  ///< a step inside an open window behind the front: of T+ in the positive phase, of T− after it (unit: 1)
    double speedFraction = 0.5;         ///< no voxel moves more than this many voxels per step (unit: voxels)
};

enum class CollisionMethod { None, Pairwise, Buckets, TreeLookup };
template <>
struct EnumNames<CollisionMethod> {
    static constexpr std::pair<CollisionMethod, const char*> kNames[] = {{CollisionMethod::None, "none"},
                                                                         {CollisionMethod::Pairwise, "pairwise"},
                                                                         {CollisionMethod::Buckets, "buckets"},
                                                                         {CollisionMethod::TreeLookup, "tree-lookup"}};
};

struct CollisionSettings {
    CollisionMethod method = CollisionMethod::TreeLookup;
    double restitution = 0.2;   ///< between bodies (unit: fraction)
    double friction = 0.6;      ///< between bodies, Coulomb coefficient (unit: 1)
    int solverIterations = 12;  ///< sequential-impulse sweeps over all contacts (unit: 1)
    /// The time step halves while any contact is deeper than this, and recovers when none is
    /// (the paper's adaptive step) (unit: voxels).
    double penetrationToleranceVoxels = 0.25;
};

// Keys and ranges (src/dynamics/Settings.cpp).
template <>
const std::vector<Field<WorldSettings>>& fieldTable<WorldSettings>();
template <>
const std::vector<Field<SleepSettings>>& fieldTable<SleepSettings>();
template <>
const std::vector<Field<TimeStepSettings>>& fieldTable<TimeStepSettings>();
template <>
const std::vector<Field<CollisionSettings>>& fieldTable<CollisionSettings>();

}  // namespace spall
