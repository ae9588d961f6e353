// The deformable phase (issue 17): while the blast loads a body and it vibrates, the body is its
// lattice (lattice/Lattice.h), not a rigid body; once the blast has passed and the vibration has
// died down, each piece its intact bonds hold together becomes a rigid body again with exactly the
// particles' linear and angular momentum. Simulation::step calls these in its deform phase.
#pragma once

#include <spall/lattice/Lattice.h>
#include <spall/lattice/Settings.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace spall {

/// A body in the deformable phase.
struct DeformableBody {
    int64_t bodyId = 0;
    /// How its body is cut into particles (ParticleBlocks.h): what its lattice was built with,
    /// saved with a checkpoint so the lattice can be built again (restoreDeformable).
    VoxelBlocks blocks;
    Lattice lattice;
    double enteredS = 0.0;     ///< (unit: s)
    /// Until when a load holds it in the phase: the end of the last step it spent inside an open
    /// blast window, or of an impact it entered for (unit: s).
    double lastLoadedS = 0.0;
    /// An impact it entered for (lattice.impact_fracture) and has not yet taken: how long the
    /// impact loads it once its particles meet what it struck (0: none awaited), and until when
    /// it waits for that (DeformablePhase::awaitImpacts); only a lattice that entered for the
    /// impact waits, not one already in the phase that a rigid body struck (unit: s).
    double awaitedImpactS = 0.0;
    double awaitImpactUntilS = 0.0;
    /// While it waits, until anything touches or loads it, its lattice is the rigid body it was
    /// built from and coasts (Lattice::coast): its wait costs a few passes over its particles a
    /// step, not the bonds' (stepLattice).
    bool coasting = false;
    /// Per exposed face of the body (body.exposedFaces order), the particle behind it: found once,
    /// as the body keeps its faces while it is a lattice.
    std::vector<uint32_t> particleOfFace;
    /// The lattice keeps its own clock: rigid steps shorter than its stable step are gathered,
    /// their time and each particle's external impulse, and stepped as one (advanceDeformable),
    /// so a lattice steps no more often than it must while the blast front holds the rigid step
    /// short. What is gathered and not yet stepped (unit: s, N s):
    double pendingS = 0.0;
    std::vector<Eigen::Vector3d> pendingImpulseNs;
    /// The body's pose when its lattice was built: a saved lattice is built again there
    /// (restoreDeformable), so what its model took from the pose (support points, the ground's
    /// offset, bearing loads, its rest orientation) is as it was, though an anchored body that
    /// let go of its supports has moved with it since (followLattice) (unit: m).
    Eigen::Vector3d entryPositionM = Eigen::Vector3d::Zero();
    Eigen::Quaterniond entryOrientation = Eigen::Quaterniond::Identity();
    /// Per voxel particle, the id of the piece the frames last showed it in (DeformablePhase::
    /// showPieces; empty: none shown yet): a part a hand-off gives takes the id of the piece shown
    /// it holds most of, so its path in the frames runs on across the hand-off.
    std::vector<int64_t> shownIdOfParticle;
};

/// Gives each of a body's parts (handOff's, in the body's lattice's index space) the id of the
/// piece shown before (DeformableBody::shownIdOfParticle) that it is, whole: a body changes shape
/// only by splitting, and a piece shown that cracked since goes on as new ids, as a rigid body's
/// parts do (a frame's mesh for an id is that id's at every frame). A part left without one gets
/// a new id from `nextId` when `nextId` is given (and the shown ids are updated: showing),
/// otherwise kNoBodyId (leaving: the simulation names it).
void nameParts(DeformableBody& deformable, std::vector<Body>& parts, int64_t* nextId);

/// The lattice of a body entering the phase, moving with the body: a particle per voxel, or per
/// block of settings.particleVoxels³ voxels (ParticleBlocks.h) moving as the body's points there.
DeformableBody enterDeformablePhase(const Body& body, const Material& material, const LatticeSettings& settings,
                                    const StaticWorld& supports, uint64_t seed, double timeS);

/// The slowest normal impact on a rigid surface that may crack a body (lattice.impact_fracture):
/// crackingImpactSpeedMS of its material at the weakest tension its links carry, a masonry
/// piece's units' when none of its links crosses a joint (particles of `particleVoxels` voxels
/// resolving the units), else the material's (unit: m/s).
double crackingImpactSpeedMS(const Body& body, const Material& material, int particleVoxels);

/// Rebuilds a saved lattice (a checkpoint holds only its particles' state, the bond forces velocity
/// Verlet carries, and its bonds' stretch and strength) from its body; throws InputError when the saved arrays do not fit the body.
void restoreDeformable(DeformableBody& saved, const Body& body, const Material& material, const LatticeSettings& settings,
                       const StaticWorld& supports, uint64_t seed);

/// Each particle's external force for the next step: the mean force on each of the body's exposed
/// faces (body.exposedFaces order, from the loads phase; empty when nothing loads it) on the
/// particle behind the face (its block's, ParticleBlocks.h), an equal share of the body's
/// weight, and the supports' bearing loads (LatticeModel::bearingLoads) while their voxels touch them.
void setExternalForces(DeformableBody& deformable, const Body& body, const std::vector<Eigen::Vector3d>& faceForcesN, const Eigen::Vector3d& gravityMS2);

/// Advances a body's lattice over a rigid step of dtS under the external forces setExternalForces
/// left, on its own clock: the step's time and impulse are gathered, and the lattice takes as
/// many whole stable steps as the gathered time holds, under the gathered impulse's mean force;
/// the rest (less than a stable step, with its share of the impulse) waits for the next. So a
/// lattice steps no more often than it must while the blast front holds the rigid step short,
/// lagging the simulation by less than a stable step. Returns the particle-steps taken. Before
/// each lattice step it asks `abandon`, and throws StepAbandoned when it says so.
int64_t advanceDeformable(DeformableBody& deformable, double dtS, const std::function<bool()>& abandon = {});

/// One step of a body's lattice: a coast while it coasts (DeformableBody::coasting), which ends
/// once its particles have met the ground or a collider; else Lattice::step.
void stepLattice(DeformableBody& deformable, double dtS);

/// Steps what a lattice has gathered (advanceDeformable), so that its state is that of the
/// simulation's time. Returns the particle-steps taken.
int64_t catchUpDeformable(DeformableBody& deformable);

/// Particles taken as one rigid body: the motion with their linear and angular momentum (as
/// velocities: the centre's and the spin their inertia gives), at the pose that fits their places
/// best (least squares; Kabsch's rotation).
struct RigidFit {
    Eigen::Vector3d centreM = Eigen::Vector3d::Zero();
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< body frame (index h) to world
    Eigen::Vector3d velocityMS = Eigen::Vector3d::Zero();  ///< of the centre
    /// The particles' mean rest place in the lattice's body frame (index × its h) (unit: m).
    Eigen::Vector3d restCentreM = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularMomentumKgM2S = Eigen::Vector3d::Zero();  ///< about the centre
    Eigen::Vector3d angularVelocityRadS = Eigen::Vector3d::Zero();
    double kineticEnergyJ = 0.0;  ///< the particles' own, translation and spin
};
RigidFit fitRigidMotion(const Lattice& lattice, const std::vector<uint32_t>& particles);

/// Sets the body's pose and velocities to its lattice's rigid fit (as a whole), so frames, the
/// history and the other bodies' contacts see where it is. An anchored body stays put while its
/// lattice still holds to a support; once every support bond has broken (a wall rocking on its
/// opened base, issue 48) it moves with it, so its path has no jump at the hand-off.
void followLattice(Body& body, const Lattice& lattice);

/// Adds linear momentum and angular momentum (about the origin) to a lattice's free particles as
/// a rigid velocity field about their centre of mass, so that the sums over the particles change
/// by exactly these (the contact solver's impulses on its body, which it moves as a rigid body).
/// A rigid field changes no bond's stretch, bend or opening rate: nothing inside the lattice
/// feels it.
void addRigidMomentum(Lattice& lattice, const Eigen::Vector3d& linearKgMS, const Eigen::Vector3d& angularAboutOriginKgM2S);

/// A lattice's particles in pieces held together by bonds that have not broken (numbered by their
/// lowest particle), each with its vibration: the strain energy of its bonds and particles plus
/// its kinetic energy about its rigid motion; for a piece a support holds, all its kinetic
/// energy and the strain energy beyond what its dead loads held on entry
/// (LatticeModel::settledStrainJ).
struct LatticePieces {
    std::vector<uint32_t> pieceOf;                  ///< per particle
    std::vector<std::vector<uint32_t>> particles;   ///< per piece
    std::vector<char> held;                         ///< per piece: bonded to a support
    std::vector<double> vibrationJ;                 ///< per piece (unit: J)
    std::vector<int64_t> voxels;                    ///< per piece: its particles that are voxels
};
LatticePieces latticePieces(const Lattice& lattice);

/// What a hand-off now would discard, over all pieces (unit: J).
double vibrationEnergyJ(const Lattice& lattice);

/// What one voxel of the material holds elastically at its tensile strength, ft² / (2E) h³
/// (unit: J): the scale the hand-off tolerance is a fraction of.
double elasticCapacityPerVoxelJ(const Material& material, double voxelSizeM);

/// A part of a body that left the phase (handOff) carrying on in it: a lattice of the part whose
/// particles and bonds take their state from the body's lattice.
DeformableBody continueDeformable(const Body& part, const DeformableBody& whole, const Material& material, const LatticeSettings& settings,
                                  const StaticWorld& supports, uint64_t seed);

/// The body back as rigid bodies: each bond broken at hand-off (Lattice::brokenAtHandOff: broken,
/// or left with less than a stated fraction of its strength) breaks the links across its face
/// (the frames' fracture surface), each such support bond clears its voxels' anchor bits, and
/// each connected part gets its particles' best-fit pose and their rigid motion (parts that share
/// a piece of the lattice, the piece's): with a particle per voxel, exactly the particles' linear
/// and angular momentum; with blocks, their velocities (setMotionsFromFit). Anchored parts stay
/// where they are. Part ids
/// are left to the caller; with one part, it is the body.
struct HandOff {
    std::vector<Body> parts;
    int64_t brokenBonds = 0;
    int64_t brokenLinks = 0;    ///< the voxels' links the broken bonds cut (brokenBonds, with a particle per voxel)
    int64_t brokenAnchors = 0;  ///< bonds to supports (the ground, a box) that broke
};
HandOff handOff(const Body& body, const Lattice& lattice);

/// Leaving the phase, for a body the blast has passed: nothing (no parts) while no free piece is
/// quiet (vibration at most `tolerancePerParticleJ` per particle of the lattice), not all are, and the time is not
/// up; otherwise handOff's parts, each marked deformable when its piece must carry on in the
/// phase, and the vibration of the pieces that leave.
struct Departure {
    HandOff handOff;
    double discardedEnergyJ = 0.0;  ///< (unit: J)
    bool timedOut = false;          ///< the time ran out with some piece not quiet: it leaves all the same
};
Departure leaveQuietPieces(const Body& body, const Lattice& lattice, double tolerancePerParticleJ, bool timeUp);

/// Whether some piece of the lattice, cut where a hand-off would cut it (Lattice::brokenAtHandOff),
/// holds to no support while another piece exists: the lattice has come apart.
bool hasFreePieceAtHandOff(const Lattice& lattice);

/// Leaving the phase in pieces while the blast still acts (issue 48, item 3), once
/// hasFreePieceAtHandOff: handOff's parts, each that can deform (it has links or anchors) marked
/// to carry on as a lattice of its own, so that the blast loads its own faces, crack faces
/// included, and the wave passes through the gaps it leaves; a lone voxel leaves rigid.
Departure separateFreePieces(const Body& body, const Lattice& lattice);

/// Whether some bond counts as broken at hand-off (Lattice::brokenAtHandOff): the lattice may
/// have come apart.
bool anyBondBrokenAtHandOff(const Lattice& lattice);

}  // namespace spall
