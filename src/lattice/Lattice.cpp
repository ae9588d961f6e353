#include <spall/lattice/Lattice.h>

#include <spall/core/Parallel.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace spall {

namespace {

/// Torsion constant of a square section of side a is 0.1406 a⁴ (Roark's Formulas for Stress and
/// Strain, table 10.7).
constexpr double kSquareTorsionConstant = 0.1406;

/// Rotation vector of a unit quaternion (angle × axis), the short way round.
Eigen::Vector3d rotationVector(Eigen::Quaterniond q)
{
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    const double s = q.vec().norm();
    if (s < 1e-12) return 2.0 * q.vec();
    return (2.0 * std::atan2(s, q.w()) / s) * q.vec();
}

Eigen::Vector3d axisVector(int axis)
{
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[axis] = 1.0;
    return e;
}

}  // namespace

LatticeStiffness calibrateLattice(const ElasticConstants& m, double h)
{
    if (!(m.youngsModulusPa > 0.0) || !(m.poissonRatio > -1.0 && m.poissonRatio < 0.5) || !(m.densityKgM3 > 0.0) || !(h > 0.0))
        throw std::invalid_argument("calibrateLattice: E, density and h must be positive and -1 < nu < 0.5");
    const double e = m.youngsModulusPa, nu = m.poissonRatio;
    LatticeStiffness k;
    k.shearModulusPa = e / (2.0 * (1.0 + nu));
    k.lameLambdaPa = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    k.normalNPerM = 2.0 * k.shearModulusPa * h;
    k.shearNPerM = 2.0 * k.shearModulusPa * h;
    k.bendingNmPerRad = e * h * h * h / 12.0;
    k.twistingNmPerRad = kSquareTorsionConstant * k.shearModulusPa * h * h * h;
    return k;
}

Lattice Lattice::fromBody(const Body& body, const ElasticConstants& material)
{
    Lattice lattice;
    const double h = body.voxelSizeM;
    lattice.voxelSizeM = h;
    lattice.particleMassKg = material.densityKgM3 * h * h * h;
    lattice.particleInertiaKgM2 = lattice.particleMassKg * h * h / 6.0;
    lattice.stiffness = calibrateLattice(material, h);
    // Particle numbers by voxel, in a tree of the body's own shape.
    LinkTree index(-1);
    for (auto it = body.grid->constTree().cbeginValueOn(); it; ++it) {
        index.setValueOn(it.getCoord(), int32_t(lattice.voxel.size()));
        lattice.voxel.push_back(it.getCoord());
        const Eigen::Vector3d offset = body.motion.orientation * body.voxelOffsetM(it.getCoord());
        lattice.positionM.push_back(body.motion.positionM + offset);
        lattice.velocityMS.push_back(body.motion.linearVelocityMS + body.motion.angularVelocityRadS.cross(offset));
        lattice.angularVelocityRadS.push_back(body.motion.angularVelocityRadS);
        lattice.orientation.push_back(body.motion.orientation);
        lattice.held.push_back((it.getValue() & kAnchorBit) ? 1 : 0);
        if (lattice.held.back()) lattice.velocityMS.back() = lattice.angularVelocityRadS.back() = Eigen::Vector3d::Zero();
    }
    const size_t n = lattice.voxel.size();
    lattice.externalForceN.assign(n, Eigen::Vector3d::Zero());
    lattice.mBondAcross.assign(n, {-1, -1, -1, -1, -1, -1});
    auto links = body.grid->getConstAccessor();
    openvdb::tree::ValueAccessor<const LinkTree> indices(index);
    for (uint32_t p = 0; p < n; ++p) {
        const int32_t bits = links.getValue(lattice.voxel[p]);
        for (const int face : {kPosX, kPosY, kPosZ}) {
            if (!(bits & (1 << face))) continue;
            const int32_t q = indices.getValue(lattice.voxel[p] + faceOffset(face));
            lattice.mBondAcross[p][face] = lattice.mBondAcross[q][oppositeFace(face)] = int32_t(lattice.bonds.size());
            lattice.bonds.push_back({p, uint32_t(q), faceAxis(face)});
        }
    }
    // λ condensed over the axes a particle has no bond along (σ = 0 there): λ for three axes,
    // 2μλ / (λ + 2μ) for two (plane stress), λμ / (λ + μ) for one (a bar: E = 2μ + that).
    const double lambda = lattice.stiffness.lameLambdaPa, mu = lattice.stiffness.shearModulusPa;
    lattice.mLambdaPa.resize(n);
    for (size_t p = 0; p < n; ++p) {
        int axes = 0;
        for (int axis = 0; axis < 3; ++axis) axes += lattice.mBondAcross[p][2 * axis] >= 0 || lattice.mBondAcross[p][2 * axis + 1] >= 0;
        const double condensed[4] = {0.0, lambda * mu / (lambda + mu), 2.0 * mu * lambda / (lambda + 2.0 * mu), lambda};
        lattice.mLambdaPa[p] = condensed[axes];
    }
    lattice.computeForces();
    return lattice;
}

double Lattice::stableTimeStepS() const
{
    const double h = voxelSizeM, mu = stiffness.shearModulusPa, lambda = stiffness.lameLambdaPa;
    const double omegaSquared = (24.0 * mu + 8.0 * mu + 12.0 * lambda) * h / particleMassKg;
    return 0.9 * 2.0 / std::sqrt(omegaSquared);
}

BondStrain Lattice::strainOf(const LatticeBond& bond) const
{
    const Eigen::Quaterniond& qa = orientation[bond.low];
    const Eigen::Quaterniond& qb = orientation[bond.high];
    BondStrain s;
    // Half-way between two orientations: their normalised sum (slerp at ½, as qb is near qa).
    const double sameHemisphere = qa.coeffs().dot(qb.coeffs()) >= 0.0 ? 1.0 : -1.0;
    s.frame.coeffs() = qa.coeffs() + sameHemisphere * qb.coeffs();
    s.frame.normalize();
    const Eigen::Quaterniond toFrame = s.frame.conjugate();
    s.displacementM = toFrame * (positionM[bond.high] - positionM[bond.low]) - voxelSizeM * axisVector(bond.axis);
    s.rotationRad = toFrame * rotationVector(qb * qa.conjugate());
    return s;
}

void Lattice::computeStrains()
{
    mStrain.resize(bonds.size());
    forEachIndex(bonds.size(), [&](size_t b) { mStrain[b] = strainOf(bonds[b]); }, kCheapGrain);
    // Each particle's tr ε: per axis, the mean normal strain of its bonds along it.
    mVolumetricStrain.assign(particleCount(), 0.0);
    forEachIndex(
        particleCount(),
        [&](size_t p) {
            double trace = 0.0;
            for (int axis = 0; axis < 3; ++axis) {
                double sum = 0.0;
                int count = 0;
                for (const int face : {2 * axis, 2 * axis + 1}) {
                    const int32_t b = mBondAcross[p][face];
                    if (b < 0) continue;
                    sum += mStrain[b].displacementM[axis] / voxelSizeM;
                    ++count;
                }
                if (count > 0) trace += sum / count;
            }
            mVolumetricStrain[p] = trace;
        },
        kCheapGrain);
}

void Lattice::computeForces()
{
    computeStrains();
    const double h = voxelSizeM;
    const LatticeStiffness& k = stiffness;
    mBondForceN.resize(bonds.size());
    mBondMomentNm.resize(bonds.size());
    mBondBendingNm.resize(bonds.size());
    // Per bond: the force on `high` (its negative acts on `low`), the moment of that force pair
    // about both centres (the same for both), and the bending and twisting moment on `high`.
    auto bondsAlongAxis = [&](size_t p, int axis) { return int(mBondAcross[p][2 * axis] >= 0) + int(mBondAcross[p][2 * axis + 1] >= 0); };
    forEachIndex(
        bonds.size(),
        [&](size_t b) {
            const LatticeBond& bond = bonds[b];
            const BondStrain& s = mStrain[b];
            const int a = bond.axis;
            // d(½ λ h³ (tr ε)²)/d(extension) summed over the two particles (tr ε averages n bonds).
            const double volumetric = h * h *
                                      (mLambdaPa[bond.low] * mVolumetricStrain[bond.low] / bondsAlongAxis(bond.low, a) +
                                       mLambdaPa[bond.high] * mVolumetricStrain[bond.high] / bondsAlongAxis(bond.high, a));
            Eigen::Vector3d local = -k.shearNPerM * s.displacementM;
            local[a] = -k.normalNPerM * s.displacementM[a] - volumetric;
            const Eigen::Vector3d force = s.frame * local;
            const Eigen::Vector3d halfArm = 0.5 * (positionM[bond.high] - positionM[bond.low]);
            mBondForceN[b] = force;
            mBondMomentNm[b] = -halfArm.cross(force);
            Eigen::Vector3d bending = -k.bendingNmPerRad * s.rotationRad;
            bending[a] = -k.twistingNmPerRad * s.rotationRad[a];
            mBondBendingNm[b] = s.frame * bending;
        },
        kCheapGrain);
    // Gather per particle, in face order: the same sums whatever the thread count.
    mForceN.resize(particleCount());
    mMomentNm.resize(particleCount());
    forEachIndex(
        particleCount(),
        [&](size_t p) {
            Eigen::Vector3d f = Eigen::Vector3d::Zero(), m = Eigen::Vector3d::Zero();
            for (int face = 0; face < kFaceCount; ++face) {
                const int32_t b = mBondAcross[p][face];
                if (b < 0) continue;
                const double sign = faceSign(face) > 0 ? -1.0 : 1.0;  // p is `low` across a + face
                f += sign * mBondForceN[b];
                m += mBondMomentNm[b] + sign * mBondBendingNm[b];
            }
            mForceN[p] = f;
            mMomentNm[p] = m;
        },
        kCheapGrain);
}

void Lattice::step(double dtS)
{
    const double halfDt = 0.5 * dtS, invMass = 1.0 / particleMassKg, invInertia = 1.0 / particleInertiaKgM2;
    // Velocity Verlet: kick half a step, drift, new forces, kick half a step. A cube's inertia is
    // the same about every axis, so ω changes by the moment alone (no gyroscopic term).
    auto kick = [&](size_t p) {
        if (held[p]) return;
        velocityMS[p] += halfDt * invMass * (mForceN[p] + externalForceN[p]);
        angularVelocityRadS[p] += halfDt * invInertia * mMomentNm[p];
    };
    forEachIndex(
        particleCount(),
        [&](size_t p) {
            kick(p);
            positionM[p] += dtS * velocityMS[p];
            const Eigen::Vector3d turn = dtS * angularVelocityRadS[p];
            const double angle = turn.norm();
            if (angle > 0.0) orientation[p] = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, turn / angle)) * orientation[p]).normalized();
        },
        kCheapGrain);
    computeForces();
    forEachIndex(particleCount(), kick, kCheapGrain);
}

double Lattice::kineticEnergyJ() const
{
    double sum = 0.0;
    for (size_t p = 0; p < particleCount(); ++p)
        sum += 0.5 * particleMassKg * velocityMS[p].squaredNorm() + 0.5 * particleInertiaKgM2 * angularVelocityRadS[p].squaredNorm();
    return sum;
}

double Lattice::strainEnergyJ() const
{
    const LatticeStiffness& k = stiffness;
    double sum = 0.0;
    for (size_t b = 0; b < bonds.size(); ++b) {
        const BondStrain s = strainOf(bonds[b]);
        const int a = bonds[b].axis;
        const double normal = s.displacementM[a], twist = s.rotationRad[a];
        sum += 0.5 * k.normalNPerM * normal * normal + 0.5 * k.shearNPerM * (s.displacementM.squaredNorm() - normal * normal) +
               0.5 * k.bendingNmPerRad * (s.rotationRad.squaredNorm() - twist * twist) + 0.5 * k.twistingNmPerRad * twist * twist;
    }
    const double volume = voxelSizeM * voxelSizeM * voxelSizeM;
    for (size_t p = 0; p < particleCount(); ++p) sum += 0.5 * mLambdaPa[p] * volume * mVolumetricStrain[p] * mVolumetricStrain[p];
    return sum;
}

Eigen::Vector3d Lattice::linearMomentum() const
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& v : velocityMS) sum += particleMassKg * v;
    return sum;
}

Eigen::Vector3d Lattice::angularMomentumAboutOrigin() const
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (size_t p = 0; p < particleCount(); ++p)
        sum += positionM[p].cross(particleMassKg * velocityMS[p]) + particleInertiaKgM2 * angularVelocityRadS[p];
    return sum;
}

}  // namespace spall
