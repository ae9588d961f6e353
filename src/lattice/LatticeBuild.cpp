// Building a lattice from a body: the bonds' calibration against the material's elasticity,
// particles and bonds from the body's voxels and links, and its anchors' support points.
#include "LatticeForEach.h"

#include <spall/lattice/RandomField.h>

#include <spall/core/Error.h>
#include <spall/core/Hash.h>
#include <spall/fracture/Fracture.h>
#include <spall/loads/Exposure.h>
#include <spall/voxel/LinkBits.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spall {

namespace {

/// Torsion constant of a square section of side a is 0.1406 a⁴ (Roark's Formulas for Stress and
/// Strain, table 10.7).
constexpr double kSquareTorsionConstant = 0.1406;

/// The normal moduli d (across the grain, along it) and λ of a lattice whose normal stiffness
/// diag(d) + λ 1 1ᵀ has the compliance of a transversely isotropic solid: E and ν across the
/// grain, E_L along it. By Sherman–Morrison the compliance is diag(1/d) − κ (1/d)(1/d)ᵀ with
/// κ = λ / (1 + λ Σ 1/d), so E_i = d_i² / (d_i − κ) and ν_ij = κ d_i / (d_j (d_i − κ)): across
/// the grain E = d (1 + ν), κ = ν d / (1 + ν); along it d_L is the root of d² − E_L d + E_L κ.
/// Isotropic (E_L = E): d = 2μ and λ Lamé's. Returns {d across, d along, λ}.
std::array<double, 3> normalModuli(double acrossPa, double poissonRatio, double alongPa)
{
    const double across = acrossPa / (1.0 + poissonRatio);
    const double kappa = poissonRatio * across / (1.0 + poissonRatio);
    const double discriminant = alongPa * alongPa - 4.0 * alongPa * kappa;
    SPALL_CHECK(discriminant >= 0.0);  // validateMaterial: E along the grain large enough
    const double along = 0.5 * (alongPa + std::sqrt(discriminant));
    const double denominator = 1.0 - kappa * (1.0 / along + 2.0 / across);
    SPALL_CHECK(denominator > 0.0);  // validateMaterial: a lattice has these E and nu
    return {across, along, kappa / denominator};
}

/// What a bond of a strength class fails at (Material's values for that class).
struct FailureValues {
    double tensilePa, fractureEnergyJPerM2, shearPa, friction, compressivePa, compressiveFractureEnergyJPerM2;
};

LatticeStiffness::Strength strengthOf(double youngsPa, const FailureValues& f, double h)
{
    LatticeStiffness::Strength s;
    s.youngsModulusPa = youngsPa;
    s.peakStretchM = f.tensilePa * h / youngsPa;
    // Voxels too large to soften (snap-back) break at the peak: the strength, which decides
    // whether a body breaks, is kept, and what the bond held beyond Gf goes back to its
    // particles (Lattice::releaseSnapEnergies).
    s.zeroTractionStretchM = std::max(2.0 * f.fractureEnergyJPerM2 / f.tensilePa, s.peakStretchM);
    s.fractureEnergyJPerM2 = f.fractureEnergyJPerM2;
    s.shearStrengthPa = f.shearPa;
    s.frictionCoefficient = f.friction;
    if (f.compressivePa > 0.0) {
        s.compressiveStrengthPa = f.compressivePa;
        s.confinementM = f.compressivePa / f.tensilePa;
        s.crushingPeakShorteningM = f.compressivePa * h / youngsPa;
        s.crushingEndShorteningM = std::max(2.0 * f.compressiveFractureEnergyJPerM2 / f.compressivePa, s.crushingPeakShorteningM);
    }
    return s;
}

/// The two strength classes (LatticeStiffness::strength) at particle size h.
std::array<LatticeStiffness::Strength, 2> strengthClasses(const Material& m, double h, double eAcross, double eAlong)
{
    SPALL_CHECK(m.tensileStrengthPa > 0.0 && m.fractureEnergyJPerM2 > 0.0 && m.shearStrengthPa > 0.0 && m.frictionCoefficient >= 0.0);
    const double fc = m.compressiveStrengthPa, gc = m.compressiveFractureEnergyJPerM2;
    const LatticeStiffness::Strength own =
        strengthOf(eAcross, {m.tensileStrengthPa, m.fractureEnergyJPerM2, m.shearStrengthPa, m.frictionCoefficient, fc, gc}, h);
    if (hasUnits(m) && !unitsResolvedBy(m, h)) {
        // Particles taller than a course: bonds across the courses are homogenised masonry's
        // (classifyUnitBonds), their energy in proportion, so the softening keeps its length.
        const double r = acrossCoursesStrengthRatio(m);
        return {own, strengthOf(eAcross, {r * m.tensileStrengthPa, r * m.fractureEnergyJPerM2, r * m.shearStrengthPa, m.frictionCoefficient, fc, gc}, h)};
    }
    if (hasUnits(m))  // masonry crushes as an assembly: its units as its joints
        return {own, strengthOf(eAcross, {m.unitTensileStrengthPa, m.unitFractureEnergyJPerM2, m.unitShearStrengthPa, m.unitFrictionCoefficient, fc, gc}, h)};
    if (hasGrain(m))
        return {own, strengthOf(eAlong,
                                {m.alongGrainTensileStrengthPa, m.alongGrainFractureEnergyJPerM2, m.alongGrainShearStrengthPa, m.frictionCoefficient,
                                 fc > 0.0 ? m.alongGrainCompressiveStrengthPa : 0.0, m.alongGrainCompressiveFractureEnergyJPerM2},
                                h)};
    return {own, own};
}

}  // namespace

LatticeStiffness calibrateLattice(const Material& m, double h)
{
    // The material's fields were checked where the scene was read (validateMaterial).
    SPALL_CHECK(m.youngsModulusPa > 0.0 && m.poissonRatio > -1.0 && m.poissonRatio < 0.5 && m.densityKgM3 > 0.0 && h > 0.0);
    const bool grained = hasGrain(m);
    SPALL_CHECK(!grained || (m.alongGrainYoungsModulusPa > 0.0 && m.alongGrainShearModulusPa > 0.0));
    const double eAcross = m.youngsModulusPa, eAlong = grained ? m.alongGrainYoungsModulusPa : eAcross;
    const double gAcross = eAcross / (2.0 * (1.0 + m.poissonRatio)), gAlong = grained ? m.alongGrainShearModulusPa : gAcross;
    const int grainAxis = grainAxisIndex(m);
    const auto [dAcross, dAlong, lambda] = normalModuli(eAcross, m.poissonRatio, eAlong);
    LatticeStiffness k;
    k.lameLambdaPa = lambda;
    for (int axis = 0; axis < 3; ++axis) {
        const bool along = axis == grainAxis;
        k.normalModulusPa[axis] = along ? dAlong : dAcross;
        k.normalNPerM[axis] = k.normalModulusPa[axis] * h;
        // Shear: the plane (axis, direction) holds the grain when either is its axis.
        for (int direction = 0; direction < 3; ++direction)
            k.shearNPerM[axis][direction] = direction == axis ? 0.0 : 2.0 * h * (along || direction == grainAxis ? gAlong : gAcross);
        k.bendingNmPerRad[axis] = (along ? eAlong : eAcross) * h * h * h / 12.0;
        // Twisting about the axis shears the two planes that hold it.
        k.twistingNmPerRad[axis] = kSquareTorsionConstant * (along ? gAlong : 0.5 * (gAlong + gAcross)) * h * h * h;
    }
    k.strength = strengthClasses(m, h, eAcross, eAlong);
    k.strengthRateLaw = m.strengthRateLaw;
    return k;
}

Lattice Lattice::fromBody(const Body& wholeBody, const Material& material, const StaticWorld& supports, const LatticeSettings& settings,
                          const VoxelBlocks& blocks, uint64_t seed)
{
    const Body coarse = blocks.voxels > 1 ? coarsenedBody(wholeBody, blocks) : Body();
    const Body& body = blocks.voxels > 1 ? coarse : wholeBody;
    Lattice lattice;
    lattice.mModel.blocks = blocks;
    lattice.mModel.bulkViscosity = settings.bulkViscosity;
    lattice.mModel.handOffResidualStrength = settings.handoffResidualStrength;
    // Davison–Stevens is the material's rate law in damage's terms; without one it has nothing
    // to add to the softening line (SceneSetup notes it).
    const bool rateDamage = settings.damageLaw == LatticeDamageLaw::DavisonStevens && material.strengthRateLaw != StrengthRateLaw::None;
    lattice.mModel.damageLaw = rateDamage ? LatticeDamageLaw::DavisonStevens : LatticeDamageLaw::Softening;
    lattice.mModel.dampingRatio = material.dampingRatio;
    const double h = body.voxelSizeM;
    lattice.mModel.spacingM = h;
    // The body's density; blocks share the body's mass (coarsenedBody).
    lattice.mModel.particleMassKg = body.densityKgM3 * h * h * h;
    lattice.mModel.particleInertiaKgM2 = lattice.mModel.particleMassKg * h * h / 6.0;
    lattice.mModel.stiffness = calibrateLattice(material, h);
    if (rateDamage) {
        lattice.mModel.stiffness.davisonStevens = davisonStevensFitTo(material.strengthRateLaw);
        lattice.mModel.stiffness.strengthRateLaw = StrengthRateLaw::None;
    }
    lattice.computeFailureTerms();
    lattice.mModel.ground = supports.ground;
    lattice.keepOutOf(supports);
    lattice.addVoxelParticles(body);
    // A body may rest a little below the plane (anchored within a quarter voxel of it; blocks of
    // voxels reach lower than their voxels): the contact plane is then where its cubes rest, so
    // a particle whose ground bond breaks is not thrown up onto the plane.
    if (lattice.mModel.ground.enabled)
        for (const Eigen::Vector3d& x : lattice.state.positionM)
            lattice.mModel.ground.offsetM = std::min(lattice.mModel.ground.offsetM, lattice.mModel.ground.normal.dot(x) - 0.5 * h);
    lattice.addLinkBonds(body);
    lattice.addSupportBonds(body, supports);
    for (uint32_t b = 0; b < lattice.mModel.bonds.size(); ++b)
        if (lattice.mModel.held[lattice.mModel.bonds[b].low] || lattice.mModel.held[lattice.mModel.bonds[b].high]) lattice.mModel.bondsToHeld.push_back(b);
    lattice.measureColliderSlack();
    if (hasUnits(material)) lattice.classifyUnitBonds(material);
    if (hasGrain(material)) lattice.classifyGrainBonds(material);
    lattice.state.bondHistory.assign(lattice.mModel.bonds.size(), BondHistory());
    if (scattersInStrength(material)) lattice.scatterStrengths(material, seed);
    if (wholeBody.linkDamage) lattice.takeOverLinkDamage(wholeBody);
    const LatticeStiffness& k = lattice.mModel.stiffness;
    const double stiffestPa = *std::max_element(k.normalModulusPa.begin(), k.normalModulusPa.end());
    const double pWaveSpeed = std::sqrt((k.lameLambdaPa + stiffestPa) / material.densityKgM3);
    lattice.mModel.dashpotPerViscosityNSPerM = material.densityKgM3 * pWaveSpeed * h * h;
    lattice.mModel.stableStepS = spall::stableTimeStepS(k, h, lattice.mModel.particleMassKg, lattice.mModel.bulkViscosity * lattice.mModel.dashpotPerViscosityNSPerM);
    lattice.condenseVolumetricModulus();
    // The weight's share per particle as setExternalForces gives it.
    const bool settled = lattice.settleUnderDeadLoads(wholeBody.mass.massKg / double(lattice.mModel.voxelParticleCount) * supports.gravityMS2);
    lattice.refreshForces();
    if (settled) lattice.recordSettledStrainEnergies();
    return lattice;
}

void Lattice::addParticle(const openvdb::Coord& ijk, const Eigen::Vector3d& placeM, const Eigen::Vector3d& velocity, const Eigen::Vector3d& spin,
                          const Eigen::Quaterniond& q, bool isHeld)
{
    mModel.particleIndex->setValueOn(ijk, int32_t(mModel.voxel.size()));
    mModel.voxel.push_back(ijk);
    state.positionM.push_back(placeM);
    state.velocityMS.push_back(isHeld ? Eigen::Vector3d::Zero() : velocity);
    state.angularVelocityRadS.push_back(isHeld ? Eigen::Vector3d::Zero() : spin);
    state.orientation.push_back(q);
    mModel.held.push_back(isHeld ? 1 : 0);
    externalForceN.push_back(Eigen::Vector3d::Zero());
    mModel.bondAcross.push_back({-1, -1, -1, -1, -1, -1});
}

void Lattice::addVoxelParticles(const Body& body)
{
    mModel.restOrientation = body.motion.orientation;
    for (auto it = body.grid->constTree().cbeginValueOn(); it; ++it) {
        const Eigen::Vector3d offset = body.motion.orientation * body.voxelOffsetM(it.getCoord());
        addParticle(it.getCoord(), body.motion.positionM + offset, body.motion.linearVelocityMS + body.motion.angularVelocityRadS.cross(offset),
                    body.motion.angularVelocityRadS, body.motion.orientation, (it.getValue() & kAnchorBit) != 0);
    }
    mModel.voxelParticleCount = mModel.voxel.size();
}

void Lattice::addBond(uint32_t low, uint32_t high, int axis)
{
    mModel.bondAcross[low][2 * axis + 1] = mModel.bondAcross[high][2 * axis] = int32_t(mModel.bonds.size());
    mModel.bonds.push_back({low, high, axis});
}

void Lattice::addLinkBonds(const Body& body)
{
    auto links = body.grid->getConstAccessor();
    openvdb::tree::ValueAccessor<const LinkTree> indices(*mModel.particleIndex);
    for (uint32_t p = 0; p < mModel.voxelParticleCount; ++p) {
        const int32_t bits = links.getValue(mModel.voxel[p]);
        for (const int face : {kPosX, kPosY, kPosZ})
            if (bits & (1 << face)) addBond(p, uint32_t(indices.getValue(mModel.voxel[p] + faceOffset(face))), faceAxis(face));
    }
}

void Lattice::addSupportBonds(const Body& body, const StaticWorld& supports)
{
    // The face of the body's voxels that looks most directly into the ground.
    int groundFace = -1;
    if (supports.ground.enabled) {
        const Eigen::Vector3d down = body.motion.orientation.inverse() * -supports.ground.normal;
        int axis = 0;
        down.cwiseAbs().maxCoeff(&axis);
        groundFace = 2 * axis + (down[axis] > 0.0 ? 1 : 0);
    }
    mModel.groundBond.assign(mModel.voxelParticleCount, -1);
    for (uint32_t p = 0; p < mModel.voxelParticleCount; ++p) {
        if (!mModel.held[p]) continue;
        const FaceInBox hold = supportedFace(body, p, groundFace, supports.boxes);
        const int face = hold.face;
        if (face < 0) continue;
        // The support point: a held particle a voxel beyond, as if the support were more of the
        // material, joined by a bond of the material's own stiffness and strength.
        const int axis = faceAxis(face);
        const uint32_t supportPoint = uint32_t(particleCount());
        addParticle(mModel.voxel[p] + faceOffset(face), state.positionM[p] + body.motion.orientation * (mModel.spacingM * faceNormal(face)),
                    Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), body.motion.orientation, true);
        mModel.held[p] = 0;
        if (face & 1) addBond(p, supportPoint, axis);
        else addBond(supportPoint, p, axis);
        if (hold.box < 0) mModel.groundBond[p] = int32_t(mModel.bonds.size() - 1);
        else if (size_t(hold.box) < supports.pinned.size()) mModel.bonds.back().pinned = supports.pinned[size_t(hold.box)];
        if (hold.box >= 0 && size_t(hold.box) < supports.bearingPressurePa.size())
            recordBearingLoad(mModel.bonds.size() - 1, face, supports.bearingPressurePa[size_t(hold.box)],
                              size_t(hold.box) < supports.friction.size() ? supports.friction[size_t(hold.box)] : 0.0, body.motion.orientation);
    }
}

FaceInBox Lattice::supportedFace(const Body& body, uint32_t p, int groundFace, const std::vector<ObstacleBox>& boxes) const
{
    // Anchors were set within a quarter voxel of the ground (Simulation); half a voxel here only
    // tells the ground's anchors from the boxes'.
    if (groundFace >= 0 && body.voxelHeightAbovePlaneM(mModel.voxel[p], mModel.ground.normal, mModel.ground.offsetM) <= 0.5 * mModel.spacingM)
        return body.grid->tree().isValueOn(mModel.voxel[p] + faceOffset(groundFace)) ? FaceInBox() : FaceInBox{groundFace, 0.0, -1};
    return freeFaceDeepestInBoxes(body, mModel.voxel[p], boxes);
}

void Lattice::classifyUnitBonds(const Material& material)
{
    // Particles taller than a course do not resolve the units: a bond across the bed joints
    // (along z) is the joints', one across the courses homogenised masonry's (calibrateLattice).
    if (!unitsResolvedBy(material, mModel.spacingM)) {
        for (LatticeBond& bond : mModel.bonds)
            if (bond.axis != 2 && bond.low < mModel.voxelParticleCount && bond.high < mModel.voxelParticleCount) bond.strengthClass = 1;
        return;
    }
    // A voxel's centre where the object was voxelised: its index times h (Voxelise.cpp's transform).
    const auto centreOf = [&](const openvdb::Coord& v) -> Eigen::Vector3d { return Eigen::Vector3d(v.x(), v.y(), v.z()) * mModel.spacingM; };
    for (LatticeBond& bond : mModel.bonds)
        if (bond.low < mModel.voxelParticleCount && bond.high < mModel.voxelParticleCount &&
            !acrossJoint(material, centreOf(mModel.voxel[bond.low]), centreOf(mModel.voxel[bond.high])))
            bond.strengthClass = 1;
}

void Lattice::classifyGrainBonds(const Material& material)
{
    const int grainAxis = grainAxisIndex(material);
    for (LatticeBond& bond : mModel.bonds)
        if (bond.axis == grainAxis) bond.strengthClass = 1;
}

void Lattice::takeOverLinkDamage(const Body& body)
{
    const auto damage = body.linkDamage->getConstAccessor();
    const auto links = body.grid->getConstAccessor();
    for (size_t b = 0; b < mModel.bonds.size(); ++b) {
        const LatticeBond& bond = mModel.bonds[b];
        const bool anchor = std::max(bond.low, bond.high) >= mModel.voxelParticleCount;
        const int face = anchor ? -1 : 2 * bond.axis + 1;
        // A bond of blocks takes the mean over the voxel pairs its face joins, a pair whose
        // link broke counting as broken; an anchor's, the mean over its block's anchored voxels.
        double sum = 0.0;
        int count = 0;
        forEachCellOfBlock(mModel.voxel[std::min(bond.low, bond.high)], mModel.blocks, face, [&](const openvdb::Coord& v) {
            const int32_t bits = links.isValueOn(v) ? links.getValue(v) : 0;
            if (anchor && (bits & kAnchorBit)) {
                sum += damage.getValue(v)[kAnchorDamage];
                ++count;
            } else if (!anchor && links.isValueOn(v) && links.isValueOn(v + faceOffset(face))) {
                sum += (bits & (1 << face)) ? damage.getValue(v)[bond.axis] : 1.0;
                ++count;
            }
        });
        if (count > 0 && sum > 0.0) startDamaged(b, sum / count);
    }
}

double condensedLambdaPa(const LatticeStiffness& stiffness, const std::array<bool, 3>& bondedAlong)
{
    double missingCompliance = 0.0;
    for (size_t axis = 0; axis < 3; ++axis)
        if (!bondedAlong[axis]) missingCompliance += 1.0 / stiffness.normalModulusPa[axis];
    return stiffness.lameLambdaPa / (1.0 + stiffness.lameLambdaPa * missingCompliance);
}

void Lattice::condenseVolumetricModulus()
{
    mModel.lambdaPa.resize(particleCount());
    mModel.inverseBondCount.resize(particleCount());
    for (size_t p = 0; p < particleCount(); ++p) {
        std::array<bool, 3> bondedAlong{};
        for (int axis = 0; axis < 3; ++axis) {
            // A pin carries nothing along its axis, so it is no bond there.
            int count = 0;
            for (const int face : {2 * axis, 2 * axis + 1}) count += int(mModel.bondAcross[p][face] >= 0 && !mModel.bonds[size_t(mModel.bondAcross[p][face])].pinned);
            mModel.inverseBondCount[p][axis] = count > 0 ? 1.0 / count : 0.0;
            bondedAlong[size_t(axis)] = count > 0;
        }
        // A particle with no bonds has no strain to weigh.
        mModel.lambdaPa[p] = condensedLambdaPa(mModel.stiffness, bondedAlong);
    }
}

void Lattice::scatterStrengths(const Material& material, uint64_t seed)
{
    if (material.strengthDistribution == StrengthDistribution::Weibull) return drawWeakestLinkStrengths(material, seed);
    // Masonry's units scatter on their own (a brick's strength is not its joint's); particles
    // taller than a course have no unit bonds, their homogenised bonds following the joints.
    const bool units = hasUnits(material) && unitsResolvedBy(material, mModel.spacingM);
    const auto isUnitBond = [&](size_t b) { return units && mModel.bonds[b].strengthClass == 1; };
    const double l = material.strengthCorrelationLengthM;
    if (material.strengthCoefficientOfVariation > 0.0)
        scatterLognormal(material.strengthCoefficientOfVariation, l, seed, [&](size_t b) { return !isUnitBond(b); });
    if (units && material.unitStrengthCoefficientOfVariation > 0.0)
        scatterLognormal(material.unitStrengthCoefficientOfVariation, l, splitmix64(seed), isUnitBond);
}

template <class Picks>
void Lattice::scatterLognormal(double coefficientOfVariation, double correlationLengthM, uint64_t seed, const Picks& scatters)
{
    const double h = mModel.spacingM;
    // The bonds' midpoints in half spacings: twice the low particle's index, one more along the axis.
    Eigen::Vector3i lowest = Eigen::Vector3i::Constant(std::numeric_limits<int>::max()), highest = -lowest;
    for (const openvdb::Coord& ijk : mModel.voxel) {
        const Eigen::Vector3i twice(2 * ijk.x(), 2 * ijk.y(), 2 * ijk.z());
        lowest = lowest.cwiseMin(twice);
        highest = highest.cwiseMax(twice + Eigen::Vector3i::Ones());
    }
    const GaussianRandomFieldOnGrid field(GaussianRandomField(seed, correlationLengthM), 0.5 * h, lowest, highest);
    // The face average's variance: the variance function along each of its two sides.
    const double cov = coefficientOfVariation * varianceFunction(h, correlationLengthM);
    const double sigma = std::sqrt(std::log(1.0 + cov * cov));
    forEach(mModel.bonds.size(), [&](size_t b) {
        if (!scatters(b)) return;
        const openvdb::Coord lo = mModel.voxel[mModel.bonds[b].low];
        Eigen::Vector3i mid(2 * lo.x(), 2 * lo.y(), 2 * lo.z());
        ++mid[mModel.bonds[b].axis];
        state.bondHistory[b].strengthScale = std::exp(sigma * field.at(mid) - 0.5 * sigma * sigma);
    });
}

void Lattice::drawWeakestLinkStrengths(const Material& material, uint64_t seed)
{
    // Weakest link (Weibull 1951, J. Appl. Mech. 18:293; the law of ASTM E1300's glass failure
    // prediction model): an area A under a uniform tension σ survives with probability
    // exp(−ln 2 (A / A_ref) (σ / ft)^m), ft the median strength of A_ref. A bond stands for its
    // face, a = h², and draws its strength from the law at that area, by inverting it at a
    // uniform survival u: σ / ft = (−ln u A_ref / (ln 2 a))^(1/m). Bonds under one stress then
    // survive together with the law at their summed area, at any h.
    const double h = mModel.spacingM, m = material.strengthWeibullModulus;
    const double areaRatio = material.strengthReferenceAreaM2 / (std::log(2.0) * h * h);
    const uint64_t weibullSeed = splitmix64(seed ^ 0x57454942554C4Cull);  // not the paper's rules' draws from the same seed
    forEach(mModel.bonds.size(), [&](size_t b) {
        const LatticeBond& bond = mModel.bonds[b];
        // An anchor's bond draws apart from the link bond of its voxel along the same axis.
        const int anchor = std::max(bond.low, bond.high) >= mModel.voxelParticleCount ? 3 : 0;
        // u in (0, 1): linkRandom is in [0, 1), shifted by half its resolution.
        const double survival = 1.0 - linkRandom(weibullSeed, mModel.voxel[bond.low], bond.axis + anchor) - 0x1p-54;
        state.bondHistory[b].strengthScale = std::pow(-std::log(survival) * areaRatio, 1.0 / m);
    });
}

}  // namespace spall
