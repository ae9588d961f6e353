// The simulation and its step: Simulation::step lists the phases of a step in order, each a call
// into its own stage (docs/architecture.md, "The step"). Frames are written by runScene.
#pragma once

#include <spall/blast/Blast.h>
#include <spall/dynamics/ContactSolver.h>
#include <spall/fracture/Events.h>
#include <spall/fracture/Fracture.h>
#include <spall/scene/Scene.h>
#include <spall/lattice/DeformablePhase.h>
#include <spall/loads/BlastLoads.h>
#include <spall/voxel/Body.h>
#include <spall/voxel/Voxelise.h>

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace spall {

/// Totals since the last call to takeStepStats().
struct StepStats {
    int64_t steps = 0;
    double minDtS = 0;
    int64_t brokenLinks = 0;
    int64_t latticeParticleSteps = 0;  ///< the deformable phase's work: lattice steps times particles, over its bodies
};

/// Everything a simulation carries from one step to the next besides its scene: what a
/// checkpoint stores so that a resumed run continues bit for bit.
struct SimulationState {
    std::vector<Body> bodies;
    std::vector<FractureEvent> events;
    std::vector<DustRecord> dust;
    DeformablePhase deformable;  ///< the bodies that are lattices, in the order they entered
    std::vector<HandOffRecord> handOffs;
    double timeS = 0;
    int64_t nextId = 0;
    int64_t initialVoxels = 0;
    ContactCache contactCache;
    double penetrationStepScale = 1.0;  ///< < 1 while contacts are deeper than the tolerance
    /// Totals since the last takeStepStats(): a frame's so far, so a run stopped within a frame
    /// and resumed records the frame whole.
    StepStats stepStats;
};

/// What one step did, for checks of invariants after every step (tests/stress_main.cpp).
/// Momentum totals include the dust, and are taken around the fracture pass, where bodies
/// split: they must agree to round-off.
struct StepRecord {
    double timeS = 0;  ///< at the end of the step
    double dtS = 0;
    bool blastOpen = false;  ///< some body was inside an open pressure window during the step
    bool split = false;      ///< a body split this step
    int64_t solverContacts = 0;  ///< contact points the solver worked on
    Eigen::Vector3d linearMomentumBeforeSplit = Eigen::Vector3d::Zero();
    Eigen::Vector3d linearMomentumAfterSplit = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularMomentumBeforeSplit = Eigen::Vector3d::Zero();  ///< about the origin
    Eigen::Vector3d angularMomentumAfterSplit = Eigen::Vector3d::Zero();
};

/// A body's kinetic energy and momenta as the frames report them (Simulation::bodyMomenta).
struct BodyMomenta {
    double kineticEnergyJ = 0.0;
    Eigen::Vector3d linearMomentumKgMS = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularMomentumKgM2S = Eigen::Vector3d::Zero();  ///< about the origin
};

class Simulation {
public:
    /// Voxelises every object and places it (throws InputError for bad input, e.g. a charge
    /// inside an object). `interrupter` (may be null) can stop voxelising a large mesh
    /// (VoxeliseInterrupted).
    explicit Simulation(const Scene& scene, Interrupter* interrupter = nullptr);
    /// Continues from a saved state; `scene` is the simulation's own (Simulation::scene()).
    Simulation(const Scene& scene, SimulationState state);

    /// The state between steps (grids are shared, not copied: save it before stepping on).
    const SimulationState& state() const { return mState; }

    /// Steps (adaptively) until time t exactly; returns false, between two steps and before t,
    /// when `interrupter` asks to stop (the state is then a whole step's, fit for a checkpoint).
    /// Throws StepAbandoned from within a step when it says to give the step up (its lattices
    /// ask between their own steps): the state is then part of a step, not to be saved.
    bool advanceTo(double timeS, Interrupter* interrupter = nullptr, const std::function<void()>& afterStep = {});

    /// One step toward `targetS` (landing on it when it is near; by default the step is the one
    /// chosen). Its phases, in order: open windows, choose dt, fracture, split, hand off, enter
    /// the deformable phase, loads, integrate, deform, detect, solve (the lattices taking their
    /// bodies' impulses), correct, sleep.
    void step(double targetS = std::numeric_limits<double>::infinity());

    double timeS() const { return mState.timeS; }
    const std::vector<Body>& bodies() const { return mState.bodies; }
    const std::vector<FractureEvent>& fractureEvents() const { return mState.events; }
    const std::vector<DustRecord>& dust() const { return mState.dust; }
    const BlastField& field() const { return *mField; }
    /// The ground and colliders, built once from the scene.
    const StaticWorld& staticWorld() const { return mStaticWorld; }
    const Scene& scene() const { return mScene; }
    int64_t initialVoxelCount() const { return mState.initialVoxels; }
    /// What setting the scene up found that a user should know (mesh repairs, memory at risk).
    const std::vector<std::string>& notes() const { return mNotes; }
    StepStats takeStepStats();
    /// Per body, its kinetic energy and momenta: a body in the deformable phase its lattice's
    /// particles' (translation and spin; an anchored wall swinging on its base has them, its
    /// rigid pose none), any other its rigid motion's (issue 48).
    std::vector<BodyMomenta> bodyMomenta() const;

    /// The bodies as a frame shows them: bodies(), except that a body in the deformable phase
    /// whose lattice has come apart is shown as the parts a hand-off now would give, at their
    /// particles' poses (DeformablePhase::showPieces). A part keeps the id it is first shown
    /// with through the hand-off, so it takes one from the simulation's ids (issue 48).
    std::vector<Body> showPieces();

    /// Called after every step (costs nothing when unset).
    void setStepObserver(std::function<void(const Simulation&, const StepRecord&)> observer) { mObserver = std::move(observer); }

    /// Chooses the next step: fine while a front crosses a body, coarse in free flight, never
    /// letting a voxel of a body that could meet something travel more than a fraction of a
    /// voxel, shorter while contacts are deep.
    double chooseTimeStep(const std::vector<OpenWindow>& windows) const;

private:
    /// The paper's fracture rules on every body the blast reaches; per body, whether it lost a
    /// link or an anchor.
    std::vector<char> fractureBodies(const std::vector<OpenWindow>& windows, double dtS);
    /// Bodies that lost links split into their connected parts (or dust), in body order.
    void splitBodies(const std::vector<char>& cracked);
    /// Replaces each body i with parts[i] (when not empty): small ones become dust as the
    /// scene says, the others get ids (a part the frames have shown has its own: showPieces),
    /// and a fracture event records them.
    void replaceWithParts(std::vector<std::vector<Body>>& parts);
    /// Bodies the blast reaches become lattices (fracture.algorithm "lattice").
    void enterDeformablePhase(const std::vector<OpenWindow>& windows);
    /// Rigid bodies with links whose contacts with the ground or a collider close faster than
    /// their material may take without cracking (crackingImpactSpeedMS) become lattices
    /// (lattice.impact_fracture): their particles take the impact in the next deform phase, so
    /// their contacts with the static world leave this step's solve (of length dtS). Two bodies
    /// whose impact on each other may crack either both become lattices, and their contact
    /// leaves the solve.
    void enterOnImpact(ContactSet& contacts, double dtS);
    /// Whether a body's share of an impact closing at closingMS (`share` of it, by the
    /// impedances) may crack it: faster than a resting contact, than the fastest impact it has
    /// survived, and than crackingImpactSpeedMS.
    bool strikesHardEnoughToCrack(double closingMS, const Body& body, double share, double dtS) const;
    /// Whether two bodies' contact may crack either (strikesHardEnoughToCrack), both able to be
    /// lattices and not both lattices already; if so, each one's survived impact is raised to its share.
    bool crackingImpactBetween(const ContactManifold& m, double dtS);
    /// Each lattice of a `struck` body is held in the phase until its impact has played out;
    /// one that was not a lattice before (`wasLattice`) first waits for its particles to meet
    /// what it struck, at most as long as they take to close their lag at `closingAtEntryMS`.
    void holdForImpacts(const std::vector<char>& struck, const std::vector<char>& wasLattice, const std::vector<double>& closingAtEntryMS, double dtS);
    /// Two bodies about to meet as lattices start touching, not overlapping: a rigid step may
    /// carry a body through a thin one's particles (a block through a pane one particle thick),
    /// which the lattices' contact would then push out the far side. The rigid ones move back
    /// along the contact's normal by its depth beyond the overlap the rigid solver excuses them,
    /// shared by inverse mass as the position correction shares it; the lattices' contact
    /// excuses what overlap is left (LatticePairContact).
    void separateBeforeEntering(const ContactManifold& m);
    /// Pieces of deformable bodies the blast has passed leave the phase once their vibration has
    /// died down (all of them after lattice.max_vibration_s) and become rigid bodies again;
    /// looked for once per lattice.handoff_check_interval_s, in the step of length dtS that
    /// reaches a multiple of it.
    void handOffQuietBodies(double dtS);
    /// Each deformable body's lattice through the step under its face loads and gravity.
    void deformBodies(const FaceForces& faces, const std::vector<OpenWindow>& windows, double dtS);
    /// The solve phase: the contact solver moves a free lattice's body as a rigid body, its
    /// lattice takes the change of the body's linear and angular momentum (addRigidMomentum),
    /// and the body follows its lattice again.
    void solveContactsWithLattices(const ContactSet& contacts, double dtS);
    /// Throws SimulationError naming the first body whose pose or velocity is not finite: an
    /// unstable integration must stop the run, not reach the output as a broken transform.
    void refuseNonFiniteMotion() const;
    /// The paper's adaptive step: halve while bodies still closing on each other interpenetrate
    /// beyond the tolerance.
    void adaptStepToPenetration(double closingPenetrationM);
    /// The speed rule of chooseTimeStep for a step of at most `longestS` with the blast's
    /// `windows` open (unit: s; infinite when no body needs it).
    double speedLimitedStepS(double longestS, const std::vector<OpenWindow>& windows) const;
    std::pair<Eigen::Vector3d, Eigen::Vector3d> totalMomenta() const;
    /// A note when the memory available could not hold every voxel as a fragment of its own.
    void noteFragmentMemory();
    /// What the scene's fracture settings cannot see, as notes naming the key and what would:
    /// the paper's rules ignore impulse and shielding; masonry in particles taller than a course
    /// is homogenised.
    void noteFractureLimits();
    void noteRateDamageWithoutRateLaw();
    /// What the lattice's particles are too large to resolve, each a note naming the voxel size
    /// that would: an object two particles thick or less, a spalled zone shallower than a particle.
    void noteUnresolvedThickness();
    /// The shallowest spalled zone any charge's reflected pulse would open at a body's far face,
    /// 0 when none would spall it (unit: m).
    double shallowestSpallZoneM(size_t bodyIndex) const;
    /// A note for each charge nearer to an object than its blast data's fits reach (the
    /// pressures are held at the fits' near end there).
    void noteChargesNearerThanTheBlastData();
    /// Before a run whose deformable phase could take more than 5 minutes or 1 GB: its bound in
    /// particle-steps, time and memory, and the keys that change it.
    void noteDeformablePhaseCost();
    /// A note for each mesh object larger than 100 m or smaller than 1 cm (`extentsM` per object),
    /// naming its extent and the keys that set its unit.
    void noteImplausibleMeshSizes(const std::vector<Eigen::Vector3d>& extentsM);
    /// Setting up: each object's mesh (empty for primitives, in metres), its voxels, its body in place.
    std::vector<TriangleMesh> loadMeshes();
    VoxeliseResult voxeliseObject(const ObjectSpec& spec, const TriangleMesh& mesh, Interrupter* interrupter);
    Body placeObject(size_t index, const VoxeliseResult& vox);

    Scene mScene;
    std::unique_ptr<BlastField> mField;
    /// The ground and the colliders, built once from the scene (SceneSetup.cpp): the loads cast
    /// shadows with it, the lattices bond their anchors to it.
    StaticWorld mStaticWorld;
    SimulationState mState;  ///< everything carried from step to step (what a checkpoint saves)
    std::function<void(const Simulation&, const StepRecord&)> mObserver;
    StepRecord mRecord;  ///< filled while a step runs, for the observer
    /// A step's face loads for the deformable phase, kept so each step reuses their storage (a
    /// fine wall's hundreds of thousands of faces were allocated and zeroed page by page).
    FaceForces mFaceForces;
    Interrupter* mInterrupter = nullptr;  ///< advanceTo's, while it runs: the lattices ask it whether to give up the step
    std::vector<std::string> mNotes;
};

/// A hash of every number in the state, by its bits (bodies with their voxels and links, events,
/// dust, hand-offs, the time): equal hashes mean a bit-identical state, for the golden tests.
uint64_t stateHash(const SimulationState& state);

/// Bodies alone in a world (no charges, no fracture), for the collision benchmark and tests.
/// Steps are at most `maxStepS` and adapt as in a run (no voxel moves more than half a voxel,
/// shorter while contacts are deep), or are exactly `maxStepS` when `fixedStep`.
Simulation rigidBodySimulation(std::vector<Body> bodies, const WorldSettings& world, const CollisionSettings& collisions,
                               const SleepSettings& sleep, double maxStepS, bool fixedStep = false);

}  // namespace spall
