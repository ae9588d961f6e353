// Rigid-body motion (paper section 4.1): blast forces on exposed faces, integrators, gravity,
// drag, a ground plane with friction, and sleep.
#pragma once

#include <spall/blast/Blast.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <functional>
#include <string>
#include <vector>

namespace spall {

enum class Integrator { ExplicitEuler, SemiImplicitEuler, RungeKutta4 };
Integrator parseIntegrator(const std::string& name);  ///< explicit-euler | semi-implicit-euler | rk4
std::string toString(Integrator integrator);

struct GroundPlane {
    bool enabled = true;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, pointing out of the ground
    double offsetM = 0.0;       ///< plane: normal . x = offset (unit: m)
    double restitution = 0.2;   ///< (unit: fraction)
    double friction = 0.6;      ///< Coulomb coefficient (unit: 1)
};

/// A static, unbreakable oriented box that bodies rest on and bounce off.
struct StaticBox {
    Eigen::Vector3d centreM = Eigen::Vector3d::Zero();
    Eigen::Vector3d halfExtentM = Eigen::Vector3d::Constant(0.5);
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    double restitution = 0.2;  ///< (unit: fraction)
    double friction = 0.6;     ///< Coulomb coefficient (unit: 1)
};

struct WorldSettings {
    Eigen::Vector3d gravityMS2 = Eigen::Vector3d(0, 0, -9.81);  ///< (unit: m/s^2)
    double linearDragPerS = 0.0;   ///< F = -k m v (unit: 1/s)
    double angularDragPerS = 0.0;  ///< tau = -k I w (unit: 1/s)
    GroundPlane ground;
    std::vector<StaticBox> colliders;
    /// Faces hit head-on see the reflected pressure (Rankine–Hugoniot, blended by cos^2 of the
    /// angle of incidence) instead of the paper's side-on pressure: a face that stops the flow
    /// feels the reflected wave, 2 to 8 times the side-on one (docs/architecture.md).
    bool reflectedPressure = true;
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
    double frontFraction = 0.5;         ///< shock front moves at most this many voxels per step (unit: voxels)
    double pulseFraction = 1.0 / 32.0;  ///< steps per positive phase inside an open window (unit: fraction of T+)
    double speedFraction = 0.5;         ///< no voxel moves more than this many voxels per step (unit: voxels)
};

/// Force (N) and torque about the centre of mass (N m), world frame.
struct Wrench {
    Eigen::Vector3d forceN = Eigen::Vector3d::Zero();
    Eigen::Vector3d torqueNm = Eigen::Vector3d::Zero();
};

/// Blast load on the exposed faces of a body at a given pose: F = p h^2 |n . R| R on every face
/// facing a charge (paper eq. 4.1), summed per body, with torques. Faces are summed in fixed
/// blocks and the blocks in order, so the result does not depend on the thread count.
Wrench blastWrench(const Body& body, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& orientation,
                   const BlastField& field, const std::vector<OpenWindow>& windows, double timeS, bool reflectedPressure);

/// Everything but contacts: blast, gravity, drag.
using WrenchFunction = std::function<Wrench(double timeS, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& q,
                                            const Eigen::Vector3d& velocityMS, const Eigen::Vector3d& angularVelocityRadS)>;

/// Advances position, orientation and momenta of one body over dt. Quaternions stay unit.
void integrateBody(Body& body, double timeS, double dtS, Integrator integrator, const WrenchFunction& wrench);

/// Upper bound of the speed of any voxel of the body (unit: m/s).
inline double maxVoxelSpeedMS(const Body& body)
{
    return body.linearVelocityMS.norm() + body.angularVelocityRadS.norm() * body.boundingRadiusM;
}

/// Kinetic energy (J), linear momentum (kg m/s) and angular momentum about the origin (kg m^2/s).
double kineticEnergyJ(const Body& body);
Eigen::Vector3d linearMomentum(const Body& body);
Eigen::Vector3d angularMomentumAboutOrigin(const Body& body);

}  // namespace spall
