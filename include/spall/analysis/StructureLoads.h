// The blast's loads on a scene's objects as they stood, face by face: the peak pressure, the
// positive and negative impulse and the arrival on every exposed voxel face of each object held
// still through the whole wave, and the front face's positive impulse beside the normally
// reflected impulse of the blast data at the same range: the figures a blast engineer checks
// against a hand calculation (UFC 3-340-02 §2-15.3) and plots on P–I diagrams. `spall loads`;
// definitions in docs/loads.md.
#pragma once

#include <spall/sim/Simulation.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <openvdb/openvdb.h>

#include <functional>
#include <string>
#include <vector>

namespace spall {

/// One exposed voxel face of an object and what the blast did to it.
struct FaceLoad {
    openvdb::Coord voxel;  ///< in the object's index space
    int face = 0;          ///< voxel/LinkBits.h Face
    Eigen::Vector3d centreM = Eigen::Vector3d::Zero();  ///< world frame (unit: m)
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();   ///< outward, world frame (unit: 1)
    double peakPressurePa = 0;  ///< largest mean overpressure over a step, pushing in (unit: Pa)
    /// Of the pressure pushing in (the positive phase, and a rear face's build-up) and of the
    /// suction (the negative phase), summed over steps by the sign of their mean (unit: Pa s).
    double impulsePaS = 0, negativeImpulsePaS = 0;
    double arrivalTimeS = -1;   ///< start of the first step that loaded it; -1: never (unit: s)
};

/// The front face: the faces whose outward normal is the object's axis direction that took the
/// most impulse, and the hand calculation at the one nearest a charge (in scaled distance).
struct FrontFace {
    int face = 0;                       ///< the axis direction, voxel/LinkBits.h Face
    size_t faces = 0;
    double meanImpulsePaS = 0, maxImpulsePaS = 0, maxPeakPressurePa = 0;
    size_t nearest = 0;                 ///< index into ObjectLoads::faces
    int charge = 0;                     ///< the charge it is nearest
    double distanceM = 0, scaledDistanceMKg13 = 0, cosIncidence = 1;
    /// The blast data's normally reflected impulse and pressure at that range (Kingery–Bulmash,
    /// a surface burst as a free-air charge of twice the mass) (unit: Pa s, Pa).
    double reflectedImpulsePaS = 0, reflectedPressurePa = 0;
};

struct ObjectLoads {
    std::string name;  ///< the object's, '/' made '_' and `_<index>` appended to a repeated one
    std::vector<FaceLoad> faces;       ///< body.exposedFaces order
    /// Sum over faces of both impulses times the face's area, pushing in (unit: N s).
    Eigen::Vector3d netImpulseNS = Eigen::Vector3d::Zero();
    FrontFace front;
    double voxelSizeM = 0;
    openvdb::math::Transform::Ptr indexToWorld;  ///< the object's index space at t = 0
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< its axes to world at t = 0
};

struct StructureLoadsReport {
    std::vector<ObjectLoads> objects;  ///< the scene's objects in order
    std::vector<Eigen::Vector3d> chargesM;
    double timeStepS = 0, endTimeS = 0;
    int64_t steps = 0;
};

/// Steps the blast over the objects of a simulation that has not stepped (each body as its
/// object was placed), held still, from the first arrival to the end of the last negative phase
/// at any of them, in steps of 1/20 of the shortest positive phase they meet (peaks from substeps
/// of 1/500 of it where a wave arrives). `onStep(done,
/// total)` reports progress. Throws InputError when the scene has no charges.
StructureLoadsReport structureLoads(const Simulation& simulation, const std::function<void(int64_t, int64_t)>& onStep = {});

/// Writes OUTDIR/loads.h5 (a row per face per object, the front face's summary as attributes),
/// OUTDIR/loads.vdb (per object, grids `<name>.impulse_Pa_s` and `<name>.peak_pressure_Pa` on its
/// surface voxels, each voxel the largest of its faces) and OUTDIR/loads_front.png (the front face
/// of the object that took the most impulse, coloured by impulse); each whole or not at all.
void writeStructureLoads(const std::string& outDir, const StructureLoadsReport& report);

}  // namespace spall
