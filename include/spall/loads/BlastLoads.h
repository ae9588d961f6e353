// Loads: the blast's force and torque on the exposed faces of a body, between the free field
// (blast) and everything that moves or breaks (fracture, dynamics). The rule is a setting
// (LoadModel): blast engineering's procedure, or the paper's (section 4.1) as a baseline.
#pragma once

#include <spall/core/Wrench.h>
#include <spall/blast/Blast.h>
#include <spall/loads/Diffraction.h>
#include <spall/loads/Exposure.h>
#include <spall/loads/FacePulse.h>
#include <spall/loads/Settings.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <utility>
#include <vector>

namespace spall {

/// The nearest and farthest distances of a body's voxels' oriented bounding box from a point
/// (the nearest point to its farthest corner; unit: m). A lattice's loads act on its body's faces
/// at its rigid fit (FaceForces), so its box holds them too.
std::pair<double, double> distanceRangeM(const Body& body, const Eigen::Vector3d& pointM);
/// True when the body's distances from a charge (distanceRangeM) meet that charge's open window:
/// only then can the blast load it.
bool bodyInWindows(const Body& body, const BlastField& field, const std::vector<OpenWindow>& windows);

/// A body's outline as seen from a charge: the rectangle its bounding box covers across the
/// line of sight, "up" from the ground. Its edges are free, except one resting on the ground.
struct Silhouette {
    double halfWidthM = 0, halfHeightM = 0;
    bool onGround = false;
    double shockSpeedMS = 340.0;

    /// The height UFC 3-340-02 measures clearing over: above the ground, or from the centre
    /// when nothing is below (unit: m).
    double clearingHeightM() const { return onGround ? 2.0 * halfHeightM : halfHeightM; }
    /// UFC 3-340-02 eq. 2-4, tc = 4S/((1 + S/G) U), G the larger of the two (unit: s).
    double clearingTimeS() const;
    /// UFC 3-340-02's rear-wall rise time 4S/U, S the smaller of the clearing height and the
    /// half-width (unit: s).
    double rearRiseTimeS() const;
};
/// The outline of a group of bodies (one body, or bodies pressed together) seen from a charge,
/// with the static boxes that hold it (heldBy).
Silhouette silhouetteOf(const std::vector<const Body*>& group, const std::vector<const ObstacleBox*>& holders, const Eigen::Vector3d& chargeM,
                        double shockSpeedMS, const GroundPlane& ground);

/// The obstacles that hold a group: those within half a voxel of an anchored member's bounds,
/// and every obstacle joined to them through others that meet (a frame, the wall round it).
/// A window set in a wall of colliders is then loaded as part of the wall: its front does not
/// clear round the pane's own edges, and its rear fills as the wall's rear does (UFC 3-340-02
/// §2-15.3, front and rear walls: both follow the whole face's outline).
std::vector<const ObstacleBox*> heldBy(const std::vector<const Body*>& group, const std::vector<ObstacleBox>& obstacles);

/// Face by face loads, for bodies that are not rigid (the deformable phase): per body, the mean
/// force over the step on each exposed face (body.exposedFaces order, world frame, unit: N),
/// filled where `wanted` is set.
struct FaceForces {
    std::vector<char> wanted;
    std::vector<std::vector<Eigen::Vector3d>> forceN;
};

/// The wave that reaches one face from one charge.
struct FaceWave {
    PointPulse pulse;
    /// Unit direction the wave travels in at the face.
    Eigen::Vector3d travel = Eigen::Vector3d::UnitX();
    /// True when it reaches the face only round an obstacle (loads/Diffraction.h).
    bool diffracted = false;
};

/// The blast's loads during one step: the field and the windows open at the step's start.
class BlastLoads {
public:
    BlastLoads(const BlastField& field, const std::vector<OpenWindow>& windows, const LoadSettings& settings, const StaticWorld& geometry);

    /// Per body: whether the blast can load it this step (anchored bodies: 0, they do not move).
    std::vector<char> loadedBodies(const std::vector<Body>& bodies) const;

    /// The mean force and torque over [t, t + dt] on the body at its pose at t: per face and
    /// charge, the face's pressure history integrated over the step (blast engineering), or
    /// the paper's force sampled at t. Faces are summed in fixed blocks and the blocks in
    /// order, so the result does not depend on the thread count.
    Wrench stepWrench(const Body& body, double timeS, double dtS) const;

    /// stepWrench for every body `loaded` marks (zero for the others), in parallel, with the
    /// bodies' exposure (blast engineering): faces pressed against another body take no load,
    /// bodies pressed together clear as one outline, and a face that looks at a charge through
    /// a body or an obstacle box is in shadow and loaded as a rear face by the wave that wraps
    /// around (UFC 3-340-02 §2-15.4's rear-wall load: side-on plus rear drag, with its rise).
    /// With `faces`, the bodies it wants (loaded or not) also get their forces face by face.
    std::vector<Wrench> stepWrenches(const std::vector<Body>& bodies, const std::vector<char>& loaded, double timeS, double dtS,
                                     FaceForces* faces = nullptr) const;

    /// Per exposed face (in body.exposedFaces order): the impulse per area pushing into it over
    /// [t, t + dt] (unit: Pa s).
    std::vector<double> faceImpulsesPaS(const Body& body, double timeS, double dtS) const;

private:
    /// Calls f(faceIndex, impulse (unit: N s), arm from the centre of mass (unit: m), outward
    /// normal) for every exposed face in [firstFace, endFace) and every charge that loads it
    /// during the step. `outlines` holds the body's silhouette per window.
    /// `exposure` (may be null) says which faces are covered or in shadow; `bodyIndex` is the
    /// body's index in it.
    template <typename F>
    void forEachFaceImpulse(const Body& body, const std::vector<Silhouette>& outlines, const Exposure* exposure, size_t bodyIndex,
                            double timeS, double dtS, size_t firstFace, size_t endFace, F&& f) const;
    /// True when a face (centre, outward normal) lies on the ground, facing into it, within
    /// half a voxel: it touches no air.
    bool onGround(const Eigen::Vector3d& faceCentreM, const Eigen::Vector3d& normal, double voxelSizeM) const;
    /// The obstacle box, or the bounds of the group of the first body (outside `excludeGroup`),
    /// that the straight path from x to the charge crosses, or null.
    const ObstacleBox* shadowCaster(const Eigen::Vector3d& xM, const Eigen::Vector3d& chargeM, const Exposure* exposure,
                                    size_t excludeGroup) const;
    /// The wave at a face whose outward point is `probeM`: the direct one (travelling along
    /// `directTravel`), or when something stands between the face and the charge, the wave
    /// diffracted around it.
    FaceWave waveOnFace(const OpenWindow& window, const PointPulse& direct, const Eigen::Vector3d& probeM, const Eigen::Vector3d& directTravel,
                        const Exposure* exposure, size_t excludeGroup, double groundToleranceM) const;
    /// The group's silhouette from each open window's charge (blast engineering only).
    std::vector<Silhouette> silhouettes(const std::vector<const Body*>& group) const;
    /// stepWrench with the outlines and the faces to skip given; each face's mean force into
    /// `faceForcesN` (may be null).
    Wrench wrenchOf(const Body& body, const std::vector<Silhouette>& outlines, const Exposure* exposure, size_t bodyIndex, double timeS,
                    double dtS, std::vector<Eigen::Vector3d>* faceForcesN = nullptr) const;

    const BlastField& mField;
    const std::vector<OpenWindow>& mWindows;
    LoadSettings mSettings;
    StaticWorld mGeometry;
    /// Per window: its charge is under the ground, a free-air charge's image, the wave the
    /// ground reflects (blast/Settings.h, withGroundImages).
    std::vector<char> mFromGround;
};

}  // namespace spall
