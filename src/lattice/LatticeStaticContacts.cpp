// A lattice against the static world: the ground plane its particles press on (unless still
// bonded to their ground point) and the colliders they may not pass through, each with its
// Coulomb friction: elastic, with the surface's restitution, under impact fracture; else
// plastic. And the friction of a floor on a cracked head.
#include "LatticeForEach.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace spall {

namespace {

/// The dashpot that gives a mass `massKg` on a spring `stiffnessNPerM` the coefficient of
/// restitution `restitution` in a lone bounce when it damps only the half of the contact in
/// which the mass leaves: a damped oscillator loses ln e over that quarter period, so
/// ζ = -ln e / sqrt((π/2)² + ln² e) (the linear spring-dashpot's relation, Schwager and Pöschel,
/// Phys. Rev. E 57 (1998) 650, over half the contact), c = 2 ζ sqrt(k m). Critical for e = 0.
double dashpotForRestitutionNSPerM(double restitution, double stiffnessNPerM, double massKg)
{
    const double logE = std::log(std::max(restitution, 1e-12));
    const double zeta = restitution <= 0.0 ? 1.0 : -logE / std::sqrt(0.25 * M_PI * M_PI + logE * logE);
    return 2.0 * zeta * std::sqrt(stiffnessNPerM * massKg);
}

/// Coulomb's friction on a particle of `massKg` sliding at `slidingMS`: against it, up to
/// `limitN` (μ times the push), or what stops the sliding within the step `dtS`.
Eigen::Vector3d frictionForceN(const Eigen::Vector3d& slidingMS, double limitN, double massKg, double dtS)
{
    const double speedMS = slidingMS.norm();
    if (speedMS <= 0.0) return Eigen::Vector3d::Zero();
    return -std::min(limitN, massKg * speedMS / dtS) / speedMS * slidingMS;
}

/// How far a particle's cube at `positionM` sinks into the model's ground plane (unit: m).
double depthInGroundM(const LatticeModel& model, const Eigen::Vector3d& positionM)
{
    return model.ground.offsetM + 0.5 * model.spacingM - model.ground.normal.dot(positionM);
}

}  // namespace

bool Lattice::bondedToGround(size_t p) const
{
    return p < mModel.groundBond.size() && mModel.groundBond[p] >= 0 && bondDamage(size_t(mModel.groundBond[p])) < 1.0;
}

void Lattice::keepOutOf(const StaticWorld& supports)
{
    const LatticeStiffness& k = mModel.stiffness;
    mModel.surfaceStiffnessNPerM = *std::min_element(k.normalNPerM.begin(), k.normalNPerM.end());
    const auto contactWith = [&](double restitution, double friction) {
        return LatticeModel::SurfaceContact{mModel.surfaceStiffnessNPerM, dashpotForRestitutionNSPerM(restitution, mModel.surfaceStiffnessNPerM, mModel.particleMassKg), friction};
    };
    mModel.groundContact = contactWith(supports.ground.restitution, supports.ground.friction);
    // The particle's centre may come within a quarter edge of a box's faces (its cube sinking in
    // by up to a quarter edge); deeper, the box pushes it back out.
    const double allowedM = 0.25 * mModel.spacingM;
    mModel.keptOut.clear();
    for (size_t i = 0; i < supports.boxes.size(); ++i) {
        const ObstacleBox& box = supports.boxes[i];
        const double restitution = i < supports.restitution.size() ? supports.restitution[i] : 0.0;
        const double friction = i < supports.friction.size() ? supports.friction[i] : 0.0;
        LatticeModel::KeptOut kept{box.orientation.toRotationMatrix().transpose(), box.centreM, box.halfExtentM + Eigen::Vector3d::Constant(allowedM), {},
                                   contactWith(restitution, friction)};
        const ObstacleBox grown{box.centreM, kept.reachM, box.orientation};
        for (const Eigen::Vector3d& corner : cornersOf(grown)) kept.boundsM.extend(corner);
        mModel.keptOut.push_back(kept);
    }
}

void Lattice::addSurfaceForces(double dtS)
{
    const bool ground = mModel.ground.enabled, boxes = !mModel.keptOut.empty();
    if (mModel.elasticSurfaces && (ground || boxes))
        forEach(particleCount(), [&](size_t p) {
            if (mModel.held[p]) return;
            if (ground && !bondedToGround(p)) pressOnGround(p, dtS);
            if (boxes) pressOnColliders(p, dtS);
        });
    // Few, each on its own voxel.
    for (const LatticeModel::BearingLoad& load : mModel.bearingLoads) holdByBearing(load, dtS);
}

std::optional<Lattice::ColliderDepth> Lattice::depthInCollider(size_t p, const LatticeModel::KeptOut& box) const
{
    if (!box.boundsM.contains(state.positionM[p])) return std::nullopt;
    const Eigen::Vector3d local = box.toBox * (state.positionM[p] - box.centreM);
    const Eigen::Vector3d depth = box.reachM - local.cwiseAbs();
    if ((depth.array() <= 0.0).any()) return std::nullopt;
    int axis = 0;
    depth.minCoeff(&axis);
    return ColliderDepth{box.toBox.row(axis).transpose() * (local[axis] >= 0.0 ? 1.0 : -1.0), depth[axis]};
}

void Lattice::measureColliderSlack()
{
    mModel.colliderSlackM.assign(mModel.keptOut.empty() ? 0 : particleCount(), 0.0f);
    for (size_t p = 0; p < mModel.colliderSlackM.size(); ++p)
        for (const LatticeModel::KeptOut& box : mModel.keptOut)
            if (const auto sunk = depthInCollider(p, box)) mModel.colliderSlackM[p] = std::max(mModel.colliderSlackM[p], float(sunk->depthM));
}

void Lattice::pressOnColliders(size_t p, double dtS)
{
    for (const LatticeModel::KeptOut& box : mModel.keptOut)
        if (const auto sunk = depthInCollider(p, box); sunk && sunk->depthM > mModel.colliderSlackM[p])
            pressOn(p, sunk->outward, sunk->depthM - mModel.colliderSlackM[p], box.contact, dtS);
}

bool Lattice::bears(const LatticeModel::BearingLoad& load) const
{
    const LatticeBond& bond = mModel.bonds[load.bond];
    const double reachM = 1.25 * mModel.spacingM;
    return (state.positionM[bond.low] - state.positionM[bond.high]).norm() <= reachM;
}

void Lattice::holdByBearing(const LatticeModel::BearingLoad& load, double dtS)
{
    if (load.friction <= 0.0 || bondDamage(load.bond) < 1.0 || !bears(load)) return;
    const size_t p = load.voxel(mModel.bonds);
    const double normalN = load.forceN.norm();
    const Eigen::Vector3d across = load.forceN / normalN, v = state.velocityMS[p];
    state.bondForceN[p] += frictionForceN(v - across.dot(v) * across, load.friction * normalN, mModel.particleMassKg, dtS);
}

void Lattice::pressOnGround(size_t p, double dtS)
{
    const double depth = depthInGroundM(mModel, state.positionM[p]);
    if (depth > 0.0) pressOn(p, mModel.ground.normal, depth, mModel.groundContact, dtS);
}

void Lattice::keepOutPlastically(size_t p)
{
    if (mModel.ground.enabled && !bondedToGround(p)) {
        const double depth = depthInGroundM(mModel, state.positionM[p]);
        if (depth > 0.0) pushOut(p, mModel.ground.normal, depth, mModel.groundContact.friction);
    }
    for (const LatticeModel::KeptOut& box : mModel.keptOut)
        if (const auto sunk = depthInCollider(p, box); sunk && sunk->depthM > mModel.colliderSlackM[p])
            pushOut(p, sunk->outward, sunk->depthM - mModel.colliderSlackM[p], box.contact.friction);
}

void Lattice::pushOut(size_t p, const Eigen::Vector3d& outward, double depthM, double friction)
{
    state.positionM[p] += depthM * outward;
    Eigen::Vector3d& v = state.velocityMS[p];
    const double into = outward.dot(v);
    if (into >= 0.0) return;
    v -= into * outward;
    const Eigen::Vector3d sliding = v - outward.dot(v) * outward;
    const double slidingMS = sliding.norm();
    if (slidingMS > 0.0) v -= std::min(1.0, friction * -into / slidingMS) * sliding;
}

void Lattice::pressOn(size_t p, const Eigen::Vector3d& outward, double depthM, const LatticeModel::SurfaceContact& surface, double dtS)
{
    const Eigen::Vector3d& v = state.velocityMS[p];
    const double closingMS = -outward.dot(v);
    // Damped only as it leaves: striking, the push is the spring's alone (a dashpot then would
    // press harder than the wave the body can carry, ρ c v).
    const double normalN = std::max(0.0, surface.stiffnessNPerM * depthM + surface.dashpotNSPerM * std::min(closingMS, 0.0));
    if (normalN == 0.0) return;
    state.bondForceN[p] += normalN * outward + frictionForceN(v + closingMS * outward, surface.friction * normalN, mModel.particleMassKg, dtS);
}

}  // namespace spall
