// A force with its torque: what the loads stage gives a body and the integrator takes.
#pragma once

#include <Eigen/Core>

namespace spall {

/// Force and torque about the centre of mass, world frame.
struct Wrench {
    Eigen::Vector3d forceN = Eigen::Vector3d::Zero();    ///< (unit: N)
    Eigen::Vector3d torqueNm = Eigen::Vector3d::Zero();  ///< (unit: N m)
};

}  // namespace spall
