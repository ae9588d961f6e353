// A lattice against the static world: the ground plane its particles press on (unless still
// bonded to their ground point) and the colliders they may not pass through, each elastic, with
// the surface's restitution and Coulomb friction. And the friction of a floor on a cracked head.
#include "LatticeForEach.h"

#include <algorithm>
#include <atomic>
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

/// A rigid surface's contact with a particle of `massKg`: the spring `stiffnessNPerM` and the
/// dashpot that gives its bounce the surface's restitution.
LatticeModel::SurfaceContact rigidSurface(double stiffnessNPerM, double restitution, double friction, double massKg)
{
    return {stiffnessNPerM, dashpotForRestitutionNSPerM(restitution, stiffnessNPerM, massKg), 0.0, friction};
}

/// Coulomb's friction on a particle of `massKg` sliding at `slidingMS`: against it, up to
/// `limitN` (μ times the push), or what stops the sliding within the step `dtS`.
Eigen::Vector3d frictionForceN(const Eigen::Vector3d& slidingMS, double limitN, double massKg, double dtS)
{
    const double speedMS = slidingMS.norm();
    if (speedMS <= 0.0) return Eigen::Vector3d::Zero();
    return -std::min(limitN, massKg * speedMS / dtS) / speedMS * slidingMS;
}

/// The largest c dt / m a compliant ground's dashpot may have (Lattice::groundContact).
constexpr double kMaxDashpotStepFraction = 0.25;

/// How far a particle's cube at `positionM` sinks into the model's ground plane (unit: m).
double depthInGroundM(const LatticeModel& model, const Eigen::Vector3d& positionM)
{
    return model.ground.offsetM + 0.5 * model.spacingM - model.ground.normal.dot(positionM);
}

}  // namespace

double Lattice::surfaceStiffnessNPerM() const
{
    // A spring of twice this pressed a flat impact 8-27 % above ρ c v (docs/accuracy.md); with
    // it a particle between a bond and a surface is no stiffer than one between two bonds, so
    // the stable step stands.
    const LatticeStiffness& k = mModel.stiffness;
    return *std::min_element(k.normalNPerM.begin(), k.normalNPerM.end());
}

LatticeModel::SurfaceContact Lattice::groundContact(double dtS) const
{
    const GroundPlane& ground = mModel.ground;
    const double bodyNPerM = surfaceStiffnessNPerM();
    if (ground.youngsModulusPa <= 0.0) return rigidSurface(bodyNPerM, ground.restitution, ground.friction, mModel.particleMassKg);
    // The half-space under the patch of n faces pressing on it is a footing of radius
    // sqrt(n / π) h: its spring grows as √n (Boussinesq), so each face's is 1/√n of a lone
    // face's; the waves it sends away are each face's own (ρ c_p h²).
    const GroundCompliance face = groundCompliance(ground, mModel.spacingM);
    const double groundNPerM = face.stiffnessNPerM / std::sqrt(double(std::max<size_t>(particlesOnGround(), 1)));
    // The body's spring behind each face in series with the ground under it: the ground takes
    // `share` of the particle's motion, F = share k_g x + share² c_g dx/dt to first order in c_g.
    const double share = bodyNPerM / (bodyNPerM + groundNPerM), stiffnessNPerM = share * groundNPerM;
    // Velocity Verlet with a dashpot c on a particle of mass m is stable while (ω dt)² + 2 c dt / m
    // < 4, and the step leaves (ω dt)² up to 3.24: c dt / m at most a quarter. A ground whose
    // impedance nears the body's reaches it (c dt / m = 0.47 share² Z₂ / Z₁) and presses less than
    // Kolsky's v Z₁ Z₂ / (Z₁ + Z₂) (docs/accuracy.md, "A compliant ground").
    const double radiationNSPerM = std::min(share * share * face.dashpotNSPerM, kMaxDashpotStepFraction * mModel.particleMassKg / dtS);
    return {stiffnessNPerM, dashpotForRestitutionNSPerM(ground.restitution, stiffnessNPerM, mModel.particleMassKg), radiationNSPerM, ground.friction};
}

size_t Lattice::particlesOnGround() const
{
    std::atomic<size_t> count{0};
    forEach(particleCount(), [&](size_t p) {
        if (!mModel.held[p] && !bondedToGround(p) && depthInGroundM(mModel, state.positionM[p]) > 0.0) count.fetch_add(1, std::memory_order_relaxed);
    });
    return count.load();
}

bool Lattice::bondedToGround(size_t p) const
{
    return p < mModel.groundBond.size() && mModel.groundBond[p] >= 0 && !isBroken(size_t(mModel.groundBond[p]));
}

void Lattice::keepOutOf(const StaticWorld& supports)
{
    // The particle's centre may come within a quarter edge of a box's faces (its cube sinking in
    // by up to a quarter edge); deeper, the box pushes it back out.
    const double allowedM = 0.25 * mModel.spacingM, stiffnessNPerM = surfaceStiffnessNPerM();
    mModel.keptOut.clear();
    for (size_t i = 0; i < supports.boxes.size(); ++i) {
        const ObstacleBox& box = supports.boxes[i];
        const double restitution = i < supports.restitution.size() ? supports.restitution[i] : 0.0;
        const double friction = i < supports.friction.size() ? supports.friction[i] : 0.0;
        LatticeModel::KeptOut kept{box.orientation.toRotationMatrix().transpose(), box.centreM, box.halfExtentM + Eigen::Vector3d::Constant(allowedM), {},
                                   rigidSurface(stiffnessNPerM, restitution, friction, mModel.particleMassKg)};
        const ObstacleBox grown{box.centreM, kept.reachM, box.orientation};
        for (const Eigen::Vector3d& corner : cornersOf(grown)) kept.boundsM.extend(corner);
        mModel.keptOut.push_back(kept);
    }
}

void Lattice::addSurfaceForces(double dtS)
{
    const bool ground = mModel.ground.enabled, boxes = !mModel.keptOut.empty();
    const LatticeModel::SurfaceContact onGround = ground ? groundContact(dtS) : LatticeModel::SurfaceContact{};
    if (ground || boxes) {
        std::atomic<bool> pressed{false};
        forEach(particleCount(), [&](size_t p) {
            if (mModel.held[p]) return;
            const bool onTheGround = ground && !bondedToGround(p) && pressOnGround(p, onGround, dtS);
            if ((boxes && pressOnColliders(p, dtS)) || onTheGround) pressed.store(true, std::memory_order_relaxed);
        });
        mPressedOnASurface = mPressedOnASurface || pressed.load();
    }
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

bool Lattice::pressOnColliders(size_t p, double dtS)
{
    bool pushed = false;
    for (const LatticeModel::KeptOut& box : mModel.keptOut)
        if (const auto sunk = depthInCollider(p, box); sunk && sunk->depthM > mModel.colliderSlackM[p])
            pushed = pressOn(p, sunk->outward, sunk->depthM - mModel.colliderSlackM[p], box.contact, dtS) || pushed;
    return pushed;
}

bool Lattice::bears(const LatticeModel::BearingLoad& load) const
{
    const LatticeBond& bond = mModel.bonds[load.bond];
    const double reachM = 1.25 * mModel.spacingM;
    return (state.positionM[bond.low] - state.positionM[bond.high]).norm() <= reachM;
}

void Lattice::holdByBearing(const LatticeModel::BearingLoad& load, double dtS)
{
    if (load.friction <= 0.0 || !isBroken(load.bond) || !bears(load)) return;
    const size_t p = load.voxel(mModel.bonds);
    const double normalN = load.forceN.norm();
    const Eigen::Vector3d across = load.forceN / normalN, v = state.velocityMS[p];
    state.bondForceN[p] += frictionForceN(v - across.dot(v) * across, load.friction * normalN, mModel.particleMassKg, dtS);
}

bool Lattice::pressOnGround(size_t p, const LatticeModel::SurfaceContact& ground, double dtS)
{
    const double depth = depthInGroundM(mModel, state.positionM[p]);
    return depth > 0.0 && pressOn(p, mModel.ground.normal, depth, ground, dtS);
}

bool Lattice::pressOn(size_t p, const Eigen::Vector3d& outward, double depthM, const LatticeModel::SurfaceContact& surface, double dtS)
{
    const Eigen::Vector3d& v = state.velocityMS[p];
    const double closingMS = -outward.dot(v);
    // The restitution's dashpot acts only as it leaves: striking, the push is the spring's (a
    // dashpot then would press harder than the wave the body can carry, ρ c v), and a compliant
    // ground's, which takes the waves it carries away both ways.
    const double normalN =
        std::max(0.0, surface.stiffnessNPerM * depthM + surface.dashpotNSPerM * std::min(closingMS, 0.0) + surface.radiationNSPerM * closingMS);
    if (normalN == 0.0) return false;
    state.bondForceN[p] += normalN * outward + frictionForceN(v + closingMS * outward, surface.friction * normalN, mModel.particleMassKg, dtS);
    return true;
}

}  // namespace spall
