// Loads (paper section 4.1): the blast's force and torque on the exposed faces of a body.
// Between the free field (blast) and everything that moves or breaks (fracture, dynamics).
#pragma once

#include <spall/blast/Blast.h>
#include <spall/loads/Settings.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace spall {

/// Force and torque about the centre of mass, world frame.
struct Wrench {
    Eigen::Vector3d forceN = Eigen::Vector3d::Zero();    ///< (unit: N)
    Eigen::Vector3d torqueNm = Eigen::Vector3d::Zero();  ///< (unit: N m)
};

/// True when the body's bounding sphere meets some open window's distance range: only then can
/// the blast load it.
bool bodyInWindows(const Body& body, const BlastField& field, const std::vector<OpenWindow>& windows);

/// The blast's loads during one step: the field and the windows open at the step's start.
class BlastLoads {
public:
    BlastLoads(const BlastField& field, const std::vector<OpenWindow>& windows, const LoadSettings& settings)
        : mField(field), mWindows(windows), mSettings(settings)
    {
    }

    /// Per body: whether the blast can load it this step (anchored bodies: 0, they do not move).
    std::vector<char> loadedBodies(const std::vector<Body>& bodies) const;

    /// Load on the exposed faces at a trial pose and time: F = p h^2 |n . R| R on every face
    /// facing a charge (paper eq. 4.1), summed per body, with torques. Faces are summed in fixed
    /// blocks and the blocks in order, so the result does not depend on the thread count.
    Wrench wrench(const Body& body, double timeS, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& orientation) const;

private:
    const BlastField& mField;
    const std::vector<OpenWindow>& mWindows;
    LoadSettings mSettings;
};

}  // namespace spall
