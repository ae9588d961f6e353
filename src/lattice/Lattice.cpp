#include <spall/lattice/Lattice.h>
#include <spall/lattice/RandomField.h>

#include <spall/core/Parallel.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace spall {

namespace {

/// Below this many particles a lattice steps on one thread: dispatching a parallel loop costs
/// more than its work (the 1 296-particle cantilever test took 8.5 s in parallel).
constexpr size_t kParallelParticles = 2048;

/// Rotation vector of a unit quaternion (angle × axis), the short way round. Bonds turn by
/// small angles: there 2 atan(s/w)/s by its series (relative error below 1e-13 for s/w < 1e-3).
Eigen::Vector3d rotationVector(Eigen::Quaterniond q)
{
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    const double s2 = q.vec().squaredNorm(), w = q.w();
    if (s2 < 1e-6 * w * w) {
        const double inverseW = 1.0 / w, r2 = s2 * inverseW * inverseW;
        return (2.0 * inverseW * (1.0 - r2 / 3.0 + r2 * r2 / 5.0)) * q.vec();
    }
    const double s = std::sqrt(s2);
    return (2.0 * std::atan2(s, w) / s) * q.vec();
}

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

/// The rotation matrix of a quaternion of any length (its own normalised): one division, where
/// normalising first takes a root and four.
Eigen::Matrix3d rotationMatrixOf(const Eigen::Quaterniond& q)
{
    const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
    const double s = 2.0 / (w * w + x * x + y * y + z * z);
    const double xx = s * x * x, yy = s * y * y, zz = s * z * z, xy = s * x * y, xz = s * x * z, yz = s * y * z;
    const double wx = s * w * x, wy = s * w * y, wz = s * w * z;
    Eigen::Matrix3d r;
    r << 1.0 - yy - zz, xy - wz, xz + wy,
         xy + wz, 1.0 - xx - zz, yz - wx,
         xz - wy, yz + wx, 1.0 - xx - yy;
    return r;
}

}  // namespace

void Lattice::scatterStrengths(const Material& material, uint64_t seed)
{
    const double h = voxelSizeM, l = material.strengthCorrelationLengthM;
    const GaussianRandomField field(seed, l);
    // The face average's variance: the variance function along each of its two sides.
    const double cov = material.strengthCoefficientOfVariation * varianceFunction(h, l);
    const double sigma = std::sqrt(std::log(1.0 + cov * cov));
    forEach(bonds.size(), [&](size_t b) {
        const openvdb::Coord lo = voxel[bonds[b].low];
        Eigen::Vector3d mid = Eigen::Vector3d(lo.x(), lo.y(), lo.z()) * h;
        mid[bonds[b].axis] += 0.5 * h;
        state.bondHistory[b].strengthScale = std::exp(sigma * field.at(mid) - 0.5 * sigma * sigma);
    });
}

double Lattice::stableTimeStepS() const
{
    const LatticeStiffness& k = stiffness;
    const double shear = *std::max_element(k.shearNPerM.begin(), k.shearNPerM.end());
    const double normal = *std::max_element(k.normalNPerM.begin(), k.normalNPerM.end());
    const double omegaSquared = (12.0 * shear + 4.0 * normal + 12.0 * k.lameLambdaPa * voxelSizeM) / particleMassKg;
    return 0.9 * 2.0 / std::sqrt(omegaSquared);
}

BondStrain Lattice::strainOf(const LatticeBond& bond) const
{
    const Eigen::Quaterniond& qa = state.orientation[bond.low];
    const Eigen::Quaterniond& qb = state.orientation[bond.high];
    BondStrain s;
    if (bond.pinned) {
        // A pin measures its voxel's centre in the held point's frame, across its axis only: the
        // voxel may turn on it and slide toward or away from the support (glazing's clearance).
        s.frame = rotationMatrixOf(held[bond.low] ? qa : qb);
        s.displacementM = s.frame.transpose() * (state.positionM[bond.high] - state.positionM[bond.low]);
        s.displacementM[bond.axis] = 0.0;
        return s;
    }
    // Half-way between two orientations: their normalised sum (slerp at ½, as qb is near qa).
    const double sameHemisphere = qa.coeffs().dot(qb.coeffs()) >= 0.0 ? 1.0 : -1.0;
    Eigen::Quaterniond half;
    half.coeffs() = qa.coeffs() + sameHemisphere * qb.coeffs();
    s.frame = rotationMatrixOf(half);
    s.displacementM = s.frame.transpose() * (state.positionM[bond.high] - state.positionM[bond.low]);
    s.displacementM[bond.axis] -= voxelSizeM;
    s.rotationRad = s.frame.transpose() * rotationVector(qb * qa.conjugate());
    return s;
}

template <typename F>
void Lattice::forEach(size_t count, const F& f) const
{
    if (particleCount() >= kParallelParticles) {
        forEachIndex(count, f, kCheapGrain);
        return;
    }
    for (size_t i = 0; i < count; ++i) f(i);
}

void Lattice::computeVolumetricStrain()
{
    mVolumetricStrain.resize(particleCount());
    mVolumetricStressShare.resize(particleCount());
    const double inverseH = 1.0 / voxelSizeM;
    forEach(
        particleCount(),
        [&](size_t p) {
            double trace = 0.0;
            for (int axis = 0; axis < 3; ++axis) {
                double sum = 0.0;
                for (const int face : {2 * axis, 2 * axis + 1}) {
                    const int32_t b = mBondAcross[p][face];
                    if (b >= 0) sum += mBondTerms[size_t(b)].effectiveStretchM * inverseH;
                }
                trace += sum * mInverseBondCount[p][axis];
            }
            mVolumetricStrain[p] = trace;
            // d(½ λ h³ (tr ε)²) / d(stretch of one bond along the axis) / h³.
            mVolumetricStressShare[p] = mLambdaPa[p] * trace * mInverseBondCount[p];
        });
}

double Lattice::bondDamage(size_t b) const
{
    return damageLaw == LatticeDamageLaw::DavisonStevens ? state.bondHistory[b].rateDamage : softeningDamage(b);
}

double Lattice::softeningDamage(size_t b) const
{
    const double scale = state.bondHistory[b].strengthScale;
    const LatticeStiffness::Strength& strength = stiffness.strength[bonds[b].strengthClass];
    const double u0 = scale * strength.peakStretchM, uf = strength.zeroTractionStretchM / scale;
    const double kappa = state.bondHistory[b].damageDriverM;
    if (kappa <= u0) return 0.0;
    // A bond too large to soften breaks at its peak, whatever its strength scale.
    if (kappa >= uf || snapsAtPeak(b)) return 1.0;
    // Secant stiffness on the softening line: (1 - D) κ / u0 = (uf - κ) / (uf - u0).
    return 1.0 - (u0 / kappa) * (uf - kappa) / (uf - u0);
}

bool Lattice::snapsAtPeak(size_t b) const
{
    const LatticeStiffness::Strength& strength = stiffness.strength[bonds[b].strengthClass];
    return strength.zeroTractionStretchM <= strength.peakStretchM;
}

uint8_t Lattice::measureBond(size_t b, double dtS, bool growDamage)
{
    const LatticeBond& bond = bonds[b];
    const LatticeStiffness& k = stiffness;
    const BondStrain s = strainOf(bond);
    const int a = bond.axis;
    BondForceTerms& terms = mBondTerms[b];
    terms.armM = state.positionM[bond.high] - state.positionM[bond.low];
    const double lengthM = terms.armM.norm();
    const Eigen::Vector3d along = terms.armM * (1.0 / lengthM);
    const double openingRateMS = (state.velocityMS[bond.high] - state.velocityMS[bond.low]).dot(along);
    const double damageBefore = bondDamage(b);
    double damage = damageBefore;
    if (growDamage && growBondDamage(b, equivalentStretchM(b, s, lengthM, damage), std::abs(openingRateMS) / voxelSizeM, dtS))
        damage = bondDamage(b);
    const bool broke = damage >= 1.0 && damageBefore < 1.0;
    // What a pin held is lost where it fails (the glazing's own dissipation).
    const bool snapped = broke && damageLaw == LatticeDamageLaw::Softening && snapsAtPeak(b) && !bond.pinned;
    if (snapped) mSnapped[b] = 1;
    const double intact = 1.0 - damage, sqrtIntact = std::sqrt(intact);
    const bool opening = lengthM > voxelSizeM;
    Eigen::Vector3d local = -intact * k.shearNPerM[a] * s.displacementM;
    local[a] = -intact * k.normalNPerM[a] * s.displacementM[a];
    terms.forceOnHighN = s.frame * local;
    if (bond.pinned) {
        // Across its axis only: no contact, dashpot, moment or volumetric share.
        terms.bendingMomentNm.setZero();
        terms.effectiveStretchM = terms.volumetricAreaPerArmM = 0.0;
        return uint8_t(broke ? kBroke : 0);
    }
    // What damage took still carries compression, as contact: along the line of centres, and
    // only while the two cubes overlap. (In the bond's frame it would push apart particles that
    // have slid past each other or turned over, which feeds energy into a shattered lattice.)
    const double overlapM = voxelSizeM - lengthM;
    if (intact < 1.0 && overlapM > 0.0) terms.forceOnHighN += (1.0 - intact) * k.normalNPerM[a] * overlapM * along;
    // A crack opening carries no viscous stress either: the dashpot softens with the spring.
    if (bulkViscosity > 0.0) terms.forceOnHighN -= (opening ? intact : 1.0) * bulkViscosity * mDashpotPerViscosity * openingRateMS * along;
    Eigen::Vector3d bending = -intact * k.bendingNmPerRad[a] * s.rotationRad;
    bending[a] = -intact * k.twistingNmPerRad[a] * s.rotationRad[a];
    terms.bendingMomentNm = s.frame * bending;
    terms.effectiveStretchM = opening ? sqrtIntact * (lengthM - voxelSizeM) : lengthM - voxelSizeM;
    terms.volumetricAreaPerArmM = (opening ? sqrtIntact : 1.0) * voxelSizeM * voxelSizeM / lengthM;
    return uint8_t((snapped ? kSnapped : 0) | (broke ? kBroke : 0));
}

void Lattice::completeBondForce(size_t b)
{
    // The volumetric energy's force along the bond: d(Σ ½ λ h³ (tr ε)²) / d(length).
    const LatticeBond& bond = bonds[b];
    BondForceTerms& terms = mBondTerms[b];
    const double sharesPa = mVolumetricStressShare[bond.low][bond.axis] + mVolumetricStressShare[bond.high][bond.axis];
    terms.forceOnHighN -= (terms.volumetricAreaPerArmM * sharesPa) * terms.armM;
    // The bond acts at the face between its particles: the pair's moment about either centre
    // is the same, -(arm / 2) × force. A pin acts at its voxel's centre (its other end is held).
    terms.pairMomentNm = bond.pinned ? Eigen::Vector3d::Zero() : Eigen::Vector3d(-0.5 * terms.armM.cross(terms.forceOnHighN));
}

void Lattice::gatherBondForces(size_t p)
{
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
    for (int face = 0; face < 6; ++face) {
        const int32_t b = mBondAcross[p][face];
        if (b < 0) continue;
        const BondForceTerms& terms = mBondTerms[size_t(b)];
        if (face & 1) {  // the bond across p's +axis face: p is its low end
            force -= terms.forceOnHighN;
            moment += terms.pairMomentNm - terms.bendingMomentNm;
        } else {
            force += terms.forceOnHighN;
            moment += terms.pairMomentNm + terms.bendingMomentNm;
        }
    }
    state.bondForceN[p] = force;
    state.bondMomentNm[p] = moment;
}

double Lattice::equivalentStretchM(size_t b) const
{
    const LatticeBond& bond = bonds[b];
    return equivalentStretchM(b, strainOf(bond), (state.positionM[bond.high] - state.positionM[bond.low]).norm(), bondDamage(b));
}

Lattice::FailureTerms Lattice::failureTerms(int strengthClass, int axis) const
{
    const LatticeStiffness& k = stiffness;
    const LatticeStiffness::Strength& strength = k.strength[size_t(strengthClass)];
    const double faceAreaM2 = voxelSizeM * voxelSizeM;
    FailureTerms terms;
    terms.peakStretchM = strength.peakStretchM;
    terms.tensionIndexPerM = 1.0 / strength.peakStretchM;
    terms.shearIndexPerM = k.shearNPerM[size_t(axis)] / (faceAreaM2 * strength.shearStrengthPa);
    terms.normalIndexPerM = k.normalNPerM[size_t(axis)] / (faceAreaM2 * strength.shearStrengthPa);
    terms.indexPerPa = 1.0 / strength.shearStrengthPa;
    terms.frictionCoefficient = strength.frictionCoefficient;
    return terms;
}

void Lattice::updateFailureTerms()
{
    for (int strengthClass = 0; strengthClass < 2; ++strengthClass)
        for (int axis = 0; axis < 3; ++axis) mFailureTerms[size_t(strengthClass)][size_t(axis)] = failureTerms(strengthClass, axis);
}

double Lattice::equivalentStretchM(size_t b, const BondStrain& strain, double lengthM, double damage) const
{
    const LatticeBond& bond = bonds[b];
    const int a = bond.axis;
    const FailureTerms& terms = mFailureTerms[bond.strengthClass][size_t(a)];
    // The shear displacement: across the bond's axis in its half-way frame.
    const double normalM = strain.displacementM[a];
    const double shearIndex = terms.shearIndexPerM * std::sqrt(std::max(0.0, strain.displacementM.squaredNorm() - normalM * normalM));
    // The stretch at the face's most stretched corner: the moment the bond carries, (1 − D) of
    // its bending stiffness times θ, opens one edge by (1 − D) θ h/2 per axis across it, so the
    // outermost bonds of a bent member see the strain of its surface, E κ t/2, as a continuum
    // would (the parallel bond's σ = F/A + |M| R/I, Potyondy & Cundall 2004), not that of their
    // centres, t/2 − h/2 from the neutral axis. As the bond softens its moment goes, and its
    // opening alone carries it to the end of the softening line, so it still dissipates Gf.
    const Eigen::Vector3d& rotation = strain.rotationRad;
    const double bendingStretchM = 0.5 * voxelSizeM * (1.0 - damage) * (std::abs(rotation[(a + 1) % 3]) + std::abs(rotation[(a + 2) % 3]));
    const double stretchM = bond.pinned ? 0.0 : lengthM - voxelSizeM + bendingStretchM;  // a pin fails in shear
    double index = 0.0;
    if (stretchM >= 0.0) {
        const double tensionIndex = stretchM * terms.tensionIndexPerM;
        index = std::sqrt(tensionIndex * tensionIndex + shearIndex * shearIndex);
    } else {
        // The compression across the bond, over the shear strength: its spring's and its
        // particles' volumetric share, as the last force pass left them (a substep behind; a
        // function of the saved state).
        const double normalIndex =
            terms.normalIndexPerM * normalM + terms.indexPerPa * (mVolumetricStressShare[bond.low][a] + mVolumetricStressShare[bond.high][a]);
        index = std::max(0.0, shearIndex - terms.frictionCoefficient * std::max(0.0, -normalIndex));
    }
    return index * terms.peakStretchM;
}

bool Lattice::growBondDamage(size_t b, double equivalentStretchNowM, double strainRatePerS, double dtS)
{
    BondHistory& history = state.bondHistory[b];
    const double increaseM = equivalentStretchNowM - history.maxEquivalentStretchM;
    if (increaseM > 0.0) {
        history.maxEquivalentStretchM += increaseM;
        history.damageDriverM +=
            stiffness.strengthRateLaw != StrengthRateLaw::None ? increaseM / dynamicIncreaseFactor(stiffness.strengthRateLaw, strainRatePerS) : increaseM;
    }
    if (damageLaw == LatticeDamageLaw::DavisonStevens) {
        history.rateDamage = rateDamageAfter(b, equivalentStretchNowM, dtS);
        return true;
    }
    return increaseM > 0.0;
}

double Lattice::rateDamageAfter(size_t b, double equivalentStretchNowM, double dtS) const
{
    const BondHistory& history = state.bondHistory[b];
    const double onLine = softeningDamage(b);
    // Past the softening line's end the crack is open: broken, as in the crack band.
    if (onLine >= 1.0) return 1.0;
    const LatticeStiffness& k = stiffness;
    // Stresses in tension's terms: the bond's (its equivalent stretch on its damaged spring) and
    // what the softening line allows at its damage driver.
    const LatticeStiffness::Strength& strength = k.strength[bonds[b].strengthClass];
    const double toStressPa = strength.youngsModulusPa / voxelSizeM, peakM = history.strengthScale * strength.peakStretchM;
    const double stressPa = (1.0 - history.rateDamage) * toStressPa * equivalentStretchNowM;
    const double allowedPa = toStressPa * (history.damageDriverM <= peakM ? peakM : (1.0 - onLine) * history.damageDriverM);
    const double excessPa = stressPa - allowedPa;
    if (excessPa <= 0.0) return history.rateDamage;
    // exp(C σx) − 1 by expm1; past exp(50) the step breaks the bond anyway.
    const double rate = k.damageRatePerS * std::expm1(std::min(k.damageStressScalePerPa * excessPa, 50.0));
    return std::min(1.0, history.rateDamage + rate * dtS);
}

void Lattice::refreshForces()
{
    updateFailureTerms();
    mBondTerms.resize(bondCount());
    mSnapped.assign(bondCount(), 0);
    state.bondForceN.resize(particleCount());
    state.bondMomentNm.resize(particleCount());
    forEach(bondCount(), [&](size_t b) { measureBond(b, 0.0, false); });
    computeVolumetricStrain();
    forEach(bondCount(), [&](size_t b) { completeBondForce(b); });
    forEach(particleCount(), [&](size_t p) { gatherBondForces(p); });
    mListedAtM.clear();  // the state may have been written from outside
    updateContactCandidates();
    addContactForces();
}

void Lattice::step(double dtS)
{
    const double halfDt = 0.5 * dtS, invMass = 1.0 / particleMassKg, invInertia = 1.0 / particleInertiaKgM2;
    // Velocity Verlet: kick half a step, drift, new forces, kick half a step. A cube's inertia is
    // the same about every axis, so ω changes by the moment alone (no gyroscopic term).
    auto kick = [&](size_t p) {
        if (held[p]) return;
        state.velocityMS[p] += halfDt * invMass * (state.bondForceN[p] + externalForceN[p]);
        state.angularVelocityRadS[p] += halfDt * invInertia * state.bondMomentNm[p];
    };
    updateFailureTerms();
    forEach(particleCount(), [&](size_t p) {
        kick(p);
        state.positionM[p] += dtS * state.velocityMS[p];
        state.orientation[p] = (rotationOf(dtS * state.angularVelocityRadS[p]) * state.orientation[p]).normalized();
        if (held[p]) return;
        if (ground.enabled && !bondedToGround(p)) keepAboveGround(p);
        if (!mKeptOut.empty()) keepOutOfColliders(p);
    });
    // Damage first, from the new positions (and the velocities half-way through the step, for
    // the strain rate), then the forces from the state.
    std::atomic<uint8_t> events{0};
    forEach(bondCount(), [&](size_t b) {
        if (const uint8_t bondEvents = measureBond(b, dtS, true)) events.fetch_or(bondEvents, std::memory_order_relaxed);
    });
    if (events.load() & kBroke) mPiecesStale = true;
    computeVolumetricStrain();
    forEach(bondCount(), [&](size_t b) { completeBondForce(b); });
    forEach(particleCount(), [&](size_t p) { gatherBondForces(p); });
    updateContactCandidates();
    addContactForces();
    forEach(particleCount(), kick);
    // At the step's end, where velocity Verlet's energy is counted.
    if (events.load() & kSnapped) releaseSnapEnergies();
    dampVibration(dtS);
}

bool Lattice::bondedToGround(size_t p) const
{
    return p < mGroundBond.size() && mGroundBond[p] >= 0 && bondDamage(size_t(mGroundBond[p])) < 1.0;
}

void Lattice::keepOutOf(const std::vector<ObstacleBox>& boxes)
{
    // The particle's centre may come within a quarter edge of a box's faces (its cube sinking in
    // by up to a quarter edge); deeper, it goes back out across the nearest face.
    const double allowedM = 0.25 * voxelSizeM;
    mKeptOut.clear();
    for (const ObstacleBox& box : boxes) {
        KeptOut kept{box.orientation.toRotationMatrix().transpose(), box.centreM, box.halfExtentM + Eigen::Vector3d::Constant(allowedM), {}};
        const ObstacleBox grown{box.centreM, kept.reachM, box.orientation};
        for (const Eigen::Vector3d& corner : cornersOf(grown)) kept.boundsM.extend(corner);
        mKeptOut.push_back(kept);
    }
}

void Lattice::keepOutOfColliders(size_t p)
{
    for (const KeptOut& box : mKeptOut) {
        if (!box.boundsM.contains(state.positionM[p])) continue;
        const Eigen::Vector3d local = box.toBox * (state.positionM[p] - box.centreM);
        const Eigen::Vector3d depth = box.reachM - local.cwiseAbs();
        if ((depth.array() <= 0.0).any()) continue;
        int axis = 0;
        depth.minCoeff(&axis);
        const Eigen::Vector3d outward = box.toBox.row(axis).transpose() * (local[axis] >= 0.0 ? 1.0 : -1.0);
        state.positionM[p] += depth[axis] * outward;
        const double into = outward.dot(state.velocityMS[p]);
        if (into < 0.0) state.velocityMS[p] -= into * outward;
    }
}

void Lattice::keepAboveGround(size_t p)
{
    const double depth = ground.offsetM + 0.5 * voxelSizeM - ground.normal.dot(state.positionM[p]);
    if (depth <= 0.0) return;
    state.positionM[p] += depth * ground.normal;
    const double into = ground.normal.dot(state.velocityMS[p]);
    if (into < 0.0) state.velocityMS[p] -= into * ground.normal;
}

}  // namespace spall
