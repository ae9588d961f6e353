// The time step rule (docs/architecture.md, "Time step"): Simulation's choose-dt phase.
#include <spall/sim/Simulation.h>

#include <spall/dynamics/BroadPhase.h>
#include <spall/dynamics/Integrate.h>
#include <spall/dynamics/StaticContacts.h>
#include <spall/loads/BlastLoads.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spall {

namespace {

/// The shortest positive duration of one charge's blast between two distances (unit: s), from
/// the table at points at most 5 % apart in distance: near a charge T+ falls with distance
/// (Kinney–Graham from 57 ms W^(1/3) at Z 0.05 to 0.08 at 0.51), and Kingery–Bulmash's dips by
/// up to 14 % in places, so neither end need hold the shortest.
double shortestPositiveDurationS(const BlastField& field, int charge, double nearM, double farM)
{
    const int intervals = std::max(1, static_cast<int>(std::ceil(std::log(farM / nearM) / std::log(1.05))));
    double shortestS = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= intervals; ++i)
        shortestS = std::min(shortestS, field.tableParameters(charge, nearM * std::pow(farM / nearM, double(i) / intervals)).positiveDurationS);
    return shortestS;
}

}  // namespace

double Simulation::chooseTimeStep(const std::vector<OpenWindow>& windows) const
{
    const TimeStepSettings& ts = mScene.timeStep;
    const double h = mScene.voxelSizeM;
    // The finest a load's arrival needs resolving: a voxel, or a lattice particle when the
    // lattice's particles are blocks of voxels (each step's impulse is exact either way).
    const double front = mScene.fracture.algorithm == FractureAlgorithm::Lattice ? h * mScene.lattice.particleVoxels : h;
    const double t = mState.timeS;
    double dt = ts.maxTimeStepS;
    // Per charge, for the body at hand: its nearest and farthest distance and the blast at the
    // nearest point (looked up once, read by both rules below).
    struct Reach {
        double nearM, farM, arrivalNearS, arrivalFarS;
        double positiveEndFarS;  ///< the latest the positive phase ends anywhere up to the farthest point
        BlastParameters atNear;
    };
    std::vector<Reach> reach(mField->charges().size());
    for (const Body& body : mState.bodies) {
        for (size_t c = 0; c < reach.size(); ++c) {
            const auto [nearestM, farthestM] = distanceRangeM(body, mField->charges()[c].positionM);
            Reach& r = reach[c];
            r.nearM = std::max(nearestM, h);
            r.farM = farthestM;
            r.atNear = mField->tableParameters(static_cast<int>(c), r.nearM);
            r.arrivalNearS = mField->charges()[c].detonationTimeS + r.atNear.arrivalTimeS;
            r.arrivalFarS = mField->charges()[c].detonationTimeS + mField->tableParameters(static_cast<int>(c), r.farM).arrivalTimeS;
            r.positiveEndFarS = mField->latestPositiveEndS(static_cast<int>(c), r.farM);
        }
        for (const OpenWindow& w : windows) {
            const Reach& r = reach[w.charge];
            if (r.farM < w.minDistanceM || r.nearM > w.maxDistanceM) continue;
            // Where the front is, from the arrival times at the body's nearest and farthest
            // points (the window's edge is padded by a table cell, which is metres wide far out).
            if (t < r.arrivalNearS) continue;  // not there yet: the arrival rule below lands on it
            if (t <= r.arrivalFarS)
                dt = std::min(dt, ts.frontFraction * front / mField->shockSpeedMS(w.charge, r.nearM));  // the front is crossing the body
            else if (t < r.positiveEndFarS)
                // Behind it: resolve the shortest pulse on the body (sampled only here, where it is read).
                dt = std::min(dt, ts.pulseFraction * shortestPositiveDurationS(*mField, w.charge, r.nearM, std::max(r.farM, r.nearM)));
            else
                dt = std::min(dt, ts.pulseFraction * r.atNear.negativeDurationS);  // the suction alone, as long and slow
        }
        // Never step far over the moment a front first reaches the body: land on it, or at most
        // a crossing step past it (landing on every arrival of every charge at every fragment
        // would take steps as short as the gaps between those moments).
        for (size_t c = 0; c < reach.size(); ++c) {
            const double arrival = reach[c].arrivalNearS;
            if (arrival > t && arrival - t < dt)
                dt = std::min(dt, std::max(arrival - t, ts.frontFraction * front / mField->shockSpeedMS(static_cast<int>(c), reach[c].nearM)));
        }
    }
    dt = std::min(dt, speedLimitedStepS(std::max(dt, ts.minTimeStepS), windows));
    return std::max(dt * mState.penetrationStepScale, ts.minTimeStepS);
}

double Simulation::speedLimitedStepS(double longestS, const std::vector<OpenWindow>& windows) const
{
    // No voxel of a body that could meet something within the step moves more than
    // speedFraction of a voxel, so no contact is stepped over. A rigid body that can meet
    // nothing within the longest step at its speed is in free flight, which needs no shorter
    // step than a slow body's: its turn is made of exact rotations (rotateTorqueFree) however
    // fast it spins, and its path is stepped as every other's. One chip of a few voxels
    // spinning at thousands of rad/s had set every body's step (docs/performance.md).
    const TimeStepSettings& ts = mScene.timeStep;
    const double h = mScene.voxelSizeM;
    const std::vector<Body>& bodies = mState.bodies;
    // Per body: its fastest voxel's speed when the rule would shorten the longest step (else 0),
    // and how far it may reach within that step.
    std::vector<double> limitingSpeedMS(bodies.size(), 0.0), reachM(bodies.size(), h);
    bool anyLimits = false;
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (bodies[i].anchored || bodies[i].motion.asleep) continue;
        const double speedMS = maxVoxelSpeedMS(bodies[i]);
        reachM[i] += speedMS * longestS;
        if (ts.speedFraction * h < speedMS * longestS) limitingSpeedMS[i] = speedMS;
        anyLimits = anyLimits || limitingSpeedMS[i] > 0.0;
    }
    double dt = std::numeric_limits<double>::infinity();
    if (!anyLimits) return dt;
    const std::vector<char> nearBody = withinReachOfAnotherBody(bodies, reachM);
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (limitingSpeedMS[i] == 0.0) continue;
        // A lattice's particles step on their own clock; its rigid motion keeps the rule, as do
        // a body the blast may break within the step (its parts' shapes turn with it) and every
        // body under the integrators that do not turn it by exact rotations.
        const bool freeFlightExact = ts.integrator == Integrator::SemiImplicitEuler && !bodies[i].motion.deformable &&
                                     !bodyInWindows(bodies[i], *mField, windows);
        if (!freeFlightExact || nearBody[i] || withinReachOfStatics(bodies[i], mScene.world, reachM[i]))
            dt = std::min(dt, ts.speedFraction * h / limitingSpeedMS[i]);
    }
    return dt;
}

void Simulation::adaptStepToPenetration(double closingPenetrationM)
{
    if (closingPenetrationM > mScene.collisions.penetrationToleranceVoxels * mScene.voxelSizeM)
        mState.penetrationStepScale = std::max(0.5 * mState.penetrationStepScale, 1.0 / 64.0);
    else
        mState.penetrationStepScale = std::min(2.0 * mState.penetrationStepScale, 1.0);
}

}  // namespace spall
