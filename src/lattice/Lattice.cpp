// The lattice's step (velocity Verlet: kick, drift, the bonds' forces, kick, then the energy
// snapped bonds give back and the damping) and its stable step. The passes it calls have a file
// each: the bonds' forces (LatticeBonds.cpp), their failure (LatticeFailure.cpp), the ground and
// colliders (LatticeStaticContacts.cpp), contacts within it (LatticeContact.cpp), damping
// (LatticeDamping.cpp), energies (LatticeEnergy.cpp).
#include "LatticeForEach.h"

#include <spall/core/Error.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace spall {

namespace {

/// The rotation by `turn` (angle × axis) as a unit quaternion; for small angles by the series
/// of cos(a/2) and sin(a/2)/a (error below 1e-16 for a < 1e-3).
Eigen::Quaterniond rotationOf(const Eigen::Vector3d& turn)
{
    const double a2 = turn.squaredNorm();
    if (a2 < 1e-6) {
        const double c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0, sinc = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0;
        return Eigen::Quaterniond(c, sinc * turn.x(), sinc * turn.y(), sinc * turn.z());
    }
    const double a = std::sqrt(a2);
    return Eigen::Quaterniond(Eigen::AngleAxisd(a, turn / a));
}

}  // namespace

double Lattice::stableTimeStepS() const
{
    SPALL_CHECK(mModel.stableStepS > 0.0);  // set by fromBody; a lattice read back is rebuilt first
    return mModel.stableStepS;
}

void Lattice::refreshForces()
{
    mBondTerms.resize(bondCount());
    mBondStretch.resize(bondCount());
    mSnapped.assign(bondCount(), 0);
    mBroken.resize(bondCount());
    for (size_t b = 0; b < bondCount(); ++b) mBroken[b] = bondDamage(b) >= 1.0;
    // Crushing's scratch exists only for a material that crushes (which it then flags).
    if (canCrush()) {
        mUncrushedLambdaTracePa.resize(particleCount());
        mBondNormalStressPa.resize(bondCount());
    }
    state.bondForceN.resize(particleCount());
    state.bondMomentNm.resize(particleCount());
    measureBonds(0.0, false);
    computeVolumetricStrain();
    forEach(particleCount(), [&](size_t p) { gatherBondForces(p); });
    mListedAtM.clear();  // the state may have been written from outside
    updateContactCandidates();
    addContactForces();
    addSurfaceForces(stableTimeStepS());
}

void Lattice::step(double dtS)
{
    moveAndMeasure(dtS);
    finishStep(dtS);
}

void Lattice::kickParticle(size_t p, const HalfKick& kick)
{
    // A cube's inertia is the same about every axis, so ω changes by the moment alone (no
    // gyroscopic term).
    if (mModel.held[p]) return;
    state.velocityMS[p] += kick.perMass * (state.bondForceN[p] + externalForceN[p]);
    state.angularVelocityRadS[p] += kick.perInertia * state.bondMomentNm[p];
}

Lattice::HalfKick Lattice::halfKick(double dtS) const
{
    // Once per pass: the particles' stores may alias the model's mass, so the compiler would
    // divide again for every particle.
    const double halfDt = 0.5 * dtS;
    return {halfDt * (1.0 / mModel.particleMassKg), halfDt * (1.0 / mModel.particleInertiaKgM2)};
}

void Lattice::moveAndMeasure(double dtS)
{
    // Velocity Verlet: kick half a step, drift, new forces, kick half a step (finishStep).
    const HalfKick kick = halfKick(dtS);
    forEach(particleCount(), [&](size_t p) {
        kickParticle(p, kick);
        state.positionM[p] += dtS * state.velocityMS[p];
        state.orientation[p] = (rotationOf(dtS * state.angularVelocityRadS[p]) * state.orientation[p]).normalized();
    });
    // Damage first, from the new positions (and the velocities half-way through the step, for
    // the strain rate), then the forces from the state.
    mStepEvents = measureBonds(dtS, true);
    if (mStepEvents & kBroke) mPiecesStale = true;
    computeVolumetricStrain();
    forEach(particleCount(), [&](size_t p) { gatherBondForces(p); });
    updateContactCandidates();
    addContactForces();
    addSurfaceForces(dtS);
}

bool Lattice::movesAsARigidBody() const
{
    if (std::any_of(mModel.held.begin(), mModel.held.end(), [](uint8_t held) { return held != 0; })) return false;
    const Eigen::Vector3d& first = externalForceN.front();
    return std::all_of(externalForceN.begin(), externalForceN.end(), [&](const Eigen::Vector3d& f) { return f == first; });
}

Lattice::FreeMass Lattice::freeMass() const
{
    // Summed in order, so the result does not depend on the thread count.
    const double m = mModel.particleMassKg;
    FreeMass free;
    for (size_t p = 0; p < particleCount(); ++p) {
        if (mModel.held[p]) continue;
        free.massKg += m;
        free.centreM += m * state.positionM[p];
    }
    if (free.massKg == 0.0) return free;
    free.centreM /= free.massKg;
    for (size_t p = 0; p < particleCount(); ++p) {
        if (mModel.held[p]) continue;
        const Eigen::Vector3d r = state.positionM[p] - free.centreM;
        free.inertiaKgM2 += m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose()) + mModel.particleInertiaKgM2 * Eigen::Matrix3d::Identity();
    }
    return free;
}

void Lattice::coast(double dtS)
{
    // Velocity Verlet's first half-kick and drift for the body as a whole: its centre kicked by
    // the common force (which turns nothing about the centre) and carried on; its particles
    // turned about the centre by ω dt and given the rigid velocity field there, ω = I⁻¹ L from
    // the angular momentum they carry and their inertia turned with them, so L is kept and a
    // body whose inertia differs about its axes changes its spin as it turns (Euler's equations).
    // No particle is held (movesAsARigidBody), so all are free. Summed in order, so the result
    // does not depend on the thread count.
    const size_t n = particleCount();
    const FreeMass body = freeMass();
    Eigen::Vector3d velocityMS = Eigen::Vector3d::Zero();
    for (size_t p = 0; p < n; ++p) velocityMS += state.velocityMS[p];
    velocityMS /= double(n);
    Eigen::Vector3d angularMomentumKgM2S = Eigen::Vector3d::Zero();
    for (size_t p = 0; p < n; ++p) {
        const Eigen::Vector3d armM = state.positionM[p] - body.centreM;
        angularMomentumKgM2S += mModel.particleMassKg * armM.cross(state.velocityMS[p] - velocityMS) + mModel.particleInertiaKgM2 * state.angularVelocityRadS[p];
    }
    const Eigen::Quaterniond turn = rotationOf(dtS * body.inertiaKgM2.ldlt().solve(angularMomentumKgM2S));
    const Eigen::Matrix3d turnMatrix = turn.toRotationMatrix();
    const Eigen::Vector3d spinRadS = (turnMatrix * body.inertiaKgM2 * turnMatrix.transpose()).ldlt().solve(angularMomentumKgM2S);
    velocityMS += halfKick(dtS).perMass * externalForceN.front();
    const Eigen::Vector3d newCentreM = body.centreM + dtS * velocityMS;
    forEach(n, [&](size_t p) {
        const Eigen::Vector3d armM = turnMatrix * (state.positionM[p] - body.centreM);
        state.positionM[p] = newCentreM + armM;
        state.velocityMS[p] = velocityMS + spinRadS.cross(armM);
        state.angularVelocityRadS[p] = spinRadS;
        state.orientation[p] = (turn * state.orientation[p]).normalized();
        state.bondForceN[p].setZero();
        state.bondMomentNm[p].setZero();
    });
    mStepEvents = 0;
    addSurfaceForces(dtS);
}

void Lattice::finishStep(double dtS)
{
    const HalfKick kick = halfKick(dtS);
    forEach(particleCount(), [&](size_t p) { kickParticle(p, kick); });
    // At the step's end, where velocity Verlet's energy is counted.
    if (mStepEvents & kSnapped) releaseSnapEnergies();
    openSupportHinges();
    dampVibration(dtS);
}

}  // namespace spall
