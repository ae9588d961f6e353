// Rigid-body motion (paper section 4.1): integrators for pose and momenta under the blast,
// gravity and drag, and the body quantities the other phases read (speed, energy, momentum).
#pragma once

#include <spall/core/Wrench.h>
#include <spall/dynamics/AirDrag.h>
#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <functional>
#include <vector>

namespace spall {

/// A body the solver may move: neither anchored, asleep nor deformable.
inline bool movable(const Body& body) { return !body.anchored && !body.motion.asleep && !body.motion.deformable; }

/// A body the contact solver moves: a movable one, or a free one in the deformable phase, which
/// the solver moves as a rigid body and whose lattice then takes the change of its momenta
/// (addRigidMomentum, lattice/Deformable.h).
inline bool takesContactImpulses(const Body& body) { return !body.anchored && !body.motion.asleep; }

/// Upper bound of the speed of any voxel of the body (unit: m/s).
inline double maxVoxelSpeedMS(const Body& body)
{
    return body.motion.linearVelocityMS.norm() + body.motion.angularVelocityRadS.norm() * body.boundingRadiusM;
}

/// Every force on a body at a trial state (time, pose, velocities): blast, gravity, drag.
using WrenchFunction = std::function<Wrench(double timeS, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& q,
                                            const Eigen::Vector3d& velocityMS, const Eigen::Vector3d& angularVelocityRadS)>;

/// Advances position, orientation and momenta of one body over dt. Quaternions stay unit.
void integrateBody(Body& body, double timeS, double dtS, Integrator integrator, const WrenchFunction& wrench);

/// The integrate phase: every awake, unanchored body under gravity, the drag of still `air` and its blast load
/// (`blast[i]`, the step's mean force and torque from the loads phase; held through the step, so
/// the blast's impulse is exactly what the loads stage integrated). In parallel: each task
/// writes only its own body.
void integrateBodies(std::vector<Body>& bodies, const std::vector<Wrench>& blast, const WorldSettings& world, const Air& air,
                     Integrator integrator, double timeS, double dtS);

/// Kinetic energy (J), linear momentum (kg m/s) and angular momentum about the origin (kg m^2/s).
double kineticEnergyJ(const Body& body);
Eigen::Vector3d linearMomentum(const Body& body);
Eigen::Vector3d angularMomentumAboutOrigin(const Body& body);

}  // namespace spall
