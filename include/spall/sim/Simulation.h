// The step (DESIGN §3): blast field -> link loading -> breaks -> split; face forces -> integrate
// -> ground contacts -> sleep. Frames are written by runScene.
#pragma once

#include <spall/blast/Blast.h>
#include <spall/dynamics/Contacts.h>
#include <spall/fracture/Events.h>
#include <spall/fracture/Fracture.h>
#include <spall/io/Scene.h>
#include <spall/voxel/Body.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace spall {

/// Totals since the last call to takeStepStats().
struct StepStats {
    int64_t steps = 0;
    double minDtS = 0;
    int64_t brokenLinks = 0;
    int64_t contacts = 0;
};

/// Everything a simulation carries from one step to the next besides its scene: what a
/// checkpoint stores so that a resumed run continues bit for bit.
struct SimulationState {
    std::vector<Body> bodies;
    std::vector<DamageGrid::Ptr> damage;  ///< per body, Davison–Stevens only (else null)
    std::vector<FractureEvent> events;
    std::vector<DustRecord> dust;
    double timeS = 0;
    int64_t nextId = 0;
    int64_t initialVoxels = 0;
    ContactCache contactCache;
    double penetrationStepScale = 1.0;  ///< < 1 while contacts are deeper than the tolerance
};

/// What one step did, for checks of invariants after every step (tests/stress_main.cpp).
/// Momentum totals include the dust, and are taken around the fracture pass, where bodies
/// split: they must agree to round-off.
struct StepRecord {
    double timeS = 0;  ///< at the end of the step
    double dtS = 0;
    bool blastOpen = false;  ///< some body was inside an open pressure window during the step
    bool split = false;      ///< a body split this step
    Eigen::Vector3d linearMomentumBeforeSplit = Eigen::Vector3d::Zero();
    Eigen::Vector3d linearMomentumAfterSplit = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularMomentumBeforeSplit = Eigen::Vector3d::Zero();  ///< about the origin
    Eigen::Vector3d angularMomentumAfterSplit = Eigen::Vector3d::Zero();
};

class Simulation {
public:
    /// Voxelises every object and places it (throws InputError for bad input, e.g. a charge
    /// inside an object).
    explicit Simulation(const Scene& scene, Interrupter* interrupter = nullptr);
    /// Continues from a saved state; `scene` is the simulation's own (Simulation::scene()).
    Simulation(const Scene& scene, SimulationState state);

    /// The state between steps (grids are shared, not copied: save it before stepping on).
    const SimulationState& state() const { return mState; }

    /// Steps (adaptively) until time t exactly.
    void advanceTo(double timeS);

    double timeS() const { return mState.timeS; }
    const std::vector<Body>& bodies() const { return mState.bodies; }
    const std::vector<FractureEvent>& fractureEvents() const { return mState.events; }
    const std::vector<DustRecord>& dust() const { return mState.dust; }
    const BlastField& field() const { return *mField; }
    const Scene& scene() const { return mScene; }
    int64_t initialVoxelCount() const { return mState.initialVoxels; }
    StepStats takeStepStats();

    /// Called after every step (costs nothing when unset).
    void setStepObserver(std::function<void(const Simulation&, const StepRecord&)> observer) { mObserver = std::move(observer); }

    /// Chooses the next step: fine while a front crosses a body, coarse in free flight, and
    /// never letting a voxel travel more than a fraction of a voxel.
    double chooseTimeStep(const std::vector<OpenWindow>& windows) const;

private:
    void fractureStep(const std::vector<OpenWindow>& windows, double dtS);
    void motionStep(const std::vector<OpenWindow>& windows, double dtS);

    Scene mScene;
    std::unique_ptr<BlastField> mField;
    SimulationState mState;  ///< everything carried from step to step (what a checkpoint saves)
    StepStats mStats;
    std::function<void(const Simulation&, const StepRecord&)> mObserver;
    StepRecord mRecord;  ///< filled while a step runs, for the observer
};

}  // namespace spall
