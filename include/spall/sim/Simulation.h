// The step (DESIGN §3): blast field -> link loading -> breaks -> split; face forces -> integrate
// -> ground contacts -> sleep. Frames are written by runScene.
#pragma once

#include <spall/blast/Blast.h>
#include <spall/dynamics/Contacts.h>
#include <spall/fracture/Events.h>
#include <spall/fracture/Fracture.h>
#include <spall/io/Scene.h>
#include <spall/voxel/Body.h>

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

class Simulation {
public:
    /// Voxelises every object and places it (throws InputError for bad input, e.g. a charge
    /// inside an object).
    explicit Simulation(const Scene& scene, Interrupter* interrupter = nullptr);

    /// Steps (adaptively) until time t exactly.
    void advanceTo(double timeS);

    double timeS() const { return mTimeS; }
    const std::vector<Body>& bodies() const { return mBodies; }
    const std::vector<FractureEvent>& fractureEvents() const { return mEvents; }
    const std::vector<DustRecord>& dust() const { return mDust; }
    const BlastField& field() const { return *mField; }
    const Scene& scene() const { return mScene; }
    int64_t initialVoxelCount() const { return mInitialVoxels; }
    StepStats takeStepStats();

    /// Chooses the next step: fine while a front crosses a body, coarse in free flight, and
    /// never letting a voxel travel more than a fraction of a voxel.
    double chooseTimeStep(const std::vector<OpenWindow>& windows) const;

private:
    void fractureStep(const PressureSnapshot& pressure, double dtS);
    void motionStep(const PressureSnapshot& pressure, double dtS);

    Scene mScene;
    std::unique_ptr<BlastField> mField;
    std::vector<Body> mBodies;
    std::vector<DamageGrid::Ptr> mDamage;  ///< per body, Davison–Stevens only
    std::vector<FractureEvent> mEvents;
    std::vector<DustRecord> mDust;
    double mTimeS = 0;
    int64_t mNextId = 0;
    int64_t mInitialVoxels = 0;
    StepStats mStats;
    ContactCache mContactCache;
    double mPenetrationStepScale = 1.0;  ///< < 1 while contacts are deeper than the tolerance
};

}  // namespace spall
