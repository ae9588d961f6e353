// Aerodynamic drag on a body in flight: F = -1/2 rho_air C_d A |v| v, with C_d from Haider and
// Levenspiel's correlation for freely falling (tumbling) non-spherical particles (Powder
// Technol. 58 (1989) 63-70), taken on the body's own voxel shape.
#pragma once

#include <spall/blast/Settings.h>
#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>

namespace spall {

/// Still air of an atmosphere: density from the ideal gas law with R = 287.05 J/(kg K) for dry
/// air, dynamic viscosity from Sutherland's law (mu0 = 1.716e-5 Pa s at 273.15 K, S = 110.4 K;
/// White, Viscous Fluid Flow, 3rd ed., table 1-2).
struct Air {
    double densityKgM3 = 1.225;
    double viscosityPaS = 1.789e-5;
};
Air airOf(const Atmosphere& atmosphere);

/// Above this Reynolds number (the upper end of the sphere data the paper reviews) C_d is held at
/// its value there: a sharp-edged block has no drag crisis, its drag stays near constant.
constexpr double kHaiderLevenspielMaxReynolds = 2.6e5;

/// Haider and Levenspiel's eq. 10: C_d on the projected area of the volume-equivalent sphere,
/// at Reynolds number `reynolds` (on that sphere's diameter) and sphericity `sphericity` (surface
/// of the volume-equivalent sphere over the body's surface, 0 < phi <= 1).
double haiderLevenspielDragCoefficient(double reynolds, double sphericity);

/// What drag needs of a body's shape, fixed while the body does not split.
struct DragShape {
    double equivalentDiameterM = 0.0;  ///< diameter of the sphere of the body's volume (unit: m)
    double sphericity = 1.0;           ///< pi d^2 over the body's exposed surface (unit: 1)
};
/// From the body's voxels and exposed faces: its staircase surface, which is the shape the
/// simulation flies (a voxelised sphere has phi = 2/3 of a true one's).
DragShape dragShapeOf(const Body& body);

/// Drag force on a body of `shape` moving at `velocityMS` through still `air` (unit: N).
Eigen::Vector3d airDragForceN(const DragShape& shape, const Air& air, const Eigen::Vector3d& velocityMS);

}  // namespace spall
