#include <spall/lattice/Deformable.h>

#include <spall/core/DisjointSets.h>
#include <spall/core/Error.h>
#include <spall/fracture/Fracture.h>
#include <spall/lattice/ParticleBlocks.h>
#include <spall/voxel/LinkBits.h>

#include <Eigen/SVD>

#include <algorithm>
#include <map>
#include <numeric>
#include <stdexcept>

namespace spall {

namespace {

/// ω from angular momentum about the centre and the body-frame inertia at `rotation`.
Eigen::Vector3d angularVelocityOf(const Eigen::Vector3d& angularMomentum, const Eigen::Matrix3d& inertiaLocal, const Eigen::Matrix3d& rotation)
{
    return (rotation * inertiaLocal * rotation.transpose()).ldlt().solve(angularMomentum);
}

/// Bodies (in the same frame) that leave a fit of particles moving as the particles did: each at
/// its place in the fit's pose, with the fit's rigid velocity field there. Velocities, not
/// momenta: a part of a lattice of blocks (ParticleBlocks.h) may hold a few of a block's voxels
/// while its particle moved with the whole block's share of mass, and handing it that momentum
/// threw a 12-voxel chip of a 27-voxel block off 2.25 times faster and spinning 5 times faster
/// than its particle. A part's kinetic energy is at most its particles' (its voxels are a subset
/// of their blocks) save for the lattice's mean fill (Lattice::fromBody). `blockOffsetM` places
/// the fit's rest frame in the bodies' (blockCentreOffsetM).
void setMotionsFromFit(const std::vector<Body*>& bodies, const RigidFit& fit, const Eigen::Vector3d& blockOffsetM)
{
    for (Body* b : bodies) {
        b->motion.positionM = fit.centreM + fit.rotation * (b->mass.centreOfMassLocalM - fit.restCentreM - blockOffsetM);
        b->motion.orientation = Eigen::Quaterniond(fit.rotation).normalized();
        b->motion.linearVelocityMS = fit.velocityMS + fit.angularVelocityRadS.cross(b->motion.positionM - fit.centreM);
        b->motion.angularVelocityRadS = fit.angularVelocityRadS;
        b->motion.overlapSlackM = kOverlapUnmeasured;
    }
}

/// The lattice particle of one of the body's voxels.
uint32_t particleOfVoxel(const Lattice& lattice, const openvdb::Coord& voxel)
{
    const int32_t p = lattice.particleAt(particleCell(voxel, lattice.model().blocks));
    SPALL_CHECK(p >= 0);  // every voxel of the body has a particle
    return uint32_t(p);
}

/// A particle's place in the body frame, index h (unit: m).
Eigen::Vector3d restPlaceM(const Lattice& lattice, uint32_t p)
{
    const openvdb::Coord& v = lattice.model().voxel[p];
    return lattice.model().spacingM * Eigen::Vector3d(v.x(), v.y(), v.z());
}

/// The rigid kinetic energy of a fit: its translation and its turning as one body.
double rigidKineticEnergyJ(const Lattice& lattice, const std::vector<uint32_t>& particles, const RigidFit& fit)
{
    return 0.5 * lattice.model().particleMassKg * double(particles.size()) * fit.velocityMS.squaredNorm() + 0.5 * fit.angularVelocityRadS.dot(fit.angularMomentumKgM2S);
}

/// A body's lattice in the given blocks, moving with the body.
DeformableBody latticeInBlocks(const Body& body, const VoxelBlocks& blocks, const Material& material, const LatticeSettings& settings,
                               const StaticWorld& supports, uint64_t seed, double timeS)
{
    DeformableBody d{body.id, blocks, Lattice::fromBody(body, material, supports, settings, blocks, seed), timeS, timeS, 0.0, 0.0, false, {}, 0.0, {},
                     body.motion.positionM, body.motion.orientation, {}};
    // Faces come in leaf order, a voxel's together: a particle is looked up once per voxel.
    d.particleOfFace.reserve(body.exposedFaces.size());
    for (size_t f = 0; f < body.exposedFaces.size(); ++f)
        d.particleOfFace.push_back(f > 0 && body.exposedFaces[f].voxel == body.exposedFaces[f - 1].voxel
                                       ? d.particleOfFace.back()
                                       : particleOfVoxel(d.lattice, body.exposedFaces[f].voxel));
    return d;
}

/// The gathered impulse's mean force over the gathered time, as each particle's external force.
void applyGatheredForces(DeformableBody& deformable)
{
    Lattice& lattice = deformable.lattice;
    for (size_t p = 0; p < lattice.particleCount(); ++p) lattice.externalForceN[p] = deformable.pendingImpulseNs[p] / deformable.pendingS;
}

}  // namespace

DeformableBody enterDeformablePhase(const Body& body, const Material& material, const LatticeSettings& settings,
                                    const StaticWorld& supports, uint64_t seed, double timeS)
{
    return latticeInBlocks(body, blocksFor(body, settings.particleVoxels), material, settings, supports, seed, timeS);
}

double crackingImpactSpeedMS(const Body& body, const Material& material, int particleVoxels)
{
    if (!hasUnits(material) || !unitsResolvedBy(material, particleVoxels * body.voxelSizeM) || material.unitTensileStrengthPa <= material.tensileStrengthPa)
        return crackingImpactSpeedMS(material);
    // A voxel's centre where the object was voxelised: its index times h (classifyUnitBonds).
    const auto centreOf = [&](const openvdb::Coord& v) -> Eigen::Vector3d { return Eigen::Vector3d(v.x(), v.y(), v.z()) * body.voxelSizeM; };
    for (auto voxel = body.grid->cbeginValueOn(); voxel; ++voxel)
        for (const int face : {kPosX, kPosY, kPosZ})
            if ((*voxel & (1 << face)) && acrossJoint(material, centreOf(voxel.getCoord()), centreOf(voxel.getCoord() + faceOffset(face))))
                return crackingImpactSpeedMS(material);
    Material units = material;
    units.tensileStrengthPa = material.unitTensileStrengthPa;
    return crackingImpactSpeedMS(units);
}

void restoreDeformable(DeformableBody& saved, const Body& body, const Material& material, const LatticeSettings& settings,
                       const StaticWorld& supports, uint64_t seed)
{
    if (saved.blocks.voxels < 1 || saved.blocks.voxels > 8)
        throw InputError("saved state: the lattice of body " + std::to_string(body.id) + " has particles of " +
                         std::to_string(saved.blocks.voxels) + " voxels (1 to 8)");
    Body atEntry = body;
    atEntry.motion.positionM = saved.entryPositionM;
    atEntry.motion.orientation = saved.entryOrientation;
    DeformableBody fresh = latticeInBlocks(atEntry, saved.blocks, material, settings, supports, seed, saved.enteredS);
    fresh.lastLoadedS = saved.lastLoadedS;
    fresh.awaitedImpactS = saved.awaitedImpactS;
    fresh.awaitImpactUntilS = saved.awaitImpactUntilS;
    fresh.coasting = saved.coasting;
    Lattice& to = fresh.lattice;
    Lattice& from = saved.lattice;
    const size_t n = to.particleCount(), bonds = to.bondCount();
    if (from.state.positionM.size() != n || from.state.velocityMS.size() != n || from.state.angularVelocityRadS.size() != n || from.state.orientation.size() != n ||
        from.state.bondHistory.size() != bonds || from.state.bondForceN.size() != n || from.state.bondMomentNm.size() != n ||
        (!saved.pendingImpulseNs.empty() && saved.pendingImpulseNs.size() != n) ||
        (!saved.shownIdOfParticle.empty() && saved.shownIdOfParticle.size() != to.model().voxelParticleCount))
        throw InputError("saved state: the lattice of body " + std::to_string(body.id) + " does not fit its voxels and links");
    if (!(saved.pendingS >= 0.0 && saved.pendingS < to.stableTimeStepS()) || (saved.pendingS > 0.0) != !saved.pendingImpulseNs.empty())
        throw InputError("saved state: the lattice of body " + std::to_string(body.id) + " has a gathered time of " +
                         std::to_string(saved.pendingS) + " s that does not fit its gathered impulses");
    fresh.pendingS = saved.pendingS;
    fresh.pendingImpulseNs = std::move(saved.pendingImpulseNs);
    fresh.shownIdOfParticle = std::move(saved.shownIdOfParticle);
    to.state.positionM = std::move(from.state.positionM);
    to.state.velocityMS = std::move(from.state.velocityMS);
    to.state.angularVelocityRadS = std::move(from.state.angularVelocityRadS);
    to.state.orientation = std::move(from.state.orientation);
    to.state.bondHistory = std::move(from.state.bondHistory);
    to.refreshForces();  // the volumetric strain; the forces as the step left them come next
    to.state.bondForceN = std::move(from.state.bondForceN);
    to.state.bondMomentNm = std::move(from.state.bondMomentNm);
    saved = std::move(fresh);
}

void setExternalForces(DeformableBody& deformable, const Body& body, const std::vector<Eigen::Vector3d>& faceForcesN,
                       const Eigen::Vector3d& gravityMS2)
{
    Lattice& lattice = deformable.lattice;
    // The body's weight, shared by its particles as its mass is (blocks share it evenly).
    const Eigen::Vector3d weight = body.mass.massKg / double(lattice.model().voxelParticleCount) * gravityMS2;
    for (size_t p = 0; p < lattice.particleCount(); ++p) lattice.externalForceN[p] = lattice.model().held[p] ? Eigen::Vector3d::Zero() : weight;
    for (const LatticeModel::BearingLoad& load : lattice.model().bearingLoads)
        if (lattice.bears(load)) lattice.externalForceN[load.voxel(lattice.model().bonds)] += load.forceN;
    if (faceForcesN.empty()) return;
    SPALL_CHECK(deformable.particleOfFace.size() == faceForcesN.size());  // the lattice's own body's faces
    for (size_t f = 0; f < faceForcesN.size(); ++f) {
        const uint32_t p = deformable.particleOfFace[f];
        if (!lattice.model().held[p]) lattice.externalForceN[p] += faceForcesN[f];
    }
}

void stepLattice(DeformableBody& deformable, double dtS)
{
    if (!deformable.coasting) {
        deformable.lattice.step(dtS);
        return;
    }
    deformable.lattice.coast(dtS);
    deformable.lattice.finishStep(dtS);
    if (deformable.lattice.pressedOnASurface()) deformable.coasting = false;
}

int64_t catchUpDeformable(DeformableBody& deformable)
{
    if (deformable.pendingS <= 0.0) return 0;
    Lattice& lattice = deformable.lattice;
    applyGatheredForces(deformable);
    stepLattice(deformable, deformable.pendingS);  // shorter than a stable step
    deformable.pendingS = 0.0;
    deformable.pendingImpulseNs.clear();
    return static_cast<int64_t>(lattice.particleCount());
}

int64_t advanceDeformable(DeformableBody& deformable, double dtS, const std::function<bool()>& abandon)
{
    Lattice& lattice = deformable.lattice;
    const size_t n = lattice.particleCount();
    deformable.pendingImpulseNs.resize(n, Eigen::Vector3d::Zero());
    for (size_t p = 0; p < n; ++p) deformable.pendingImpulseNs[p] += dtS * lattice.externalForceN[p];
    deformable.pendingS += dtS;
    // Whole stable steps of what is gathered (within rounding of a whole number of them counts
    // as it), under the gathered impulse's mean force; the rest stays gathered with its share of
    // the impulse.
    const double stableS = lattice.stableTimeStepS();
    const int64_t steps = static_cast<int64_t>(std::floor(deformable.pendingS / stableS * (1.0 + 1e-12)));
    if (steps == 0) return 0;
    applyGatheredForces(deformable);
    for (int64_t i = 0; i < steps; ++i) {
        if (abandon && abandon()) throw StepAbandoned("a step of the deformable phase was given up after " + std::to_string(i) + " of its " +
                                                      std::to_string(steps) + " lattice steps");
        stepLattice(deformable, stableS);
    }
    const double leftS = deformable.pendingS - double(steps) * stableS;
    if (leftS <= 1e-12 * stableS) {
        deformable.pendingS = 0.0;
        deformable.pendingImpulseNs.clear();
    } else {
        for (size_t p = 0; p < n; ++p) deformable.pendingImpulseNs[p] *= leftS / deformable.pendingS;
        deformable.pendingS = leftS;
    }
    return steps * static_cast<int64_t>(n);
}

RigidFit fitRigidMotion(const Lattice& lattice, const std::vector<uint32_t>& particles)
{
    RigidFit fit;
    const double m = lattice.model().particleMassKg, n = double(particles.size());
    const double cubeMoment = lattice.model().spacingM * lattice.model().spacingM / 12.0;
    Eigen::Vector3d restCentre = Eigen::Vector3d::Zero();
    for (const uint32_t p : particles) {
        fit.centreM += lattice.state.positionM[p];
        fit.velocityMS += lattice.state.velocityMS[p];
        restCentre += restPlaceM(lattice, p);
    }
    fit.centreM /= n;
    fit.velocityMS /= n;
    restCentre /= n;
    fit.restCentreM = restCentre;
    // Kabsch (1976): the rotation R minimising Σ |R r_i - d_i|² is U diag(1, 1, det) Vᵀ from the
    // SVD of Σ d_i r_iᵀ; over the points of each particle's cube too (their second moment, h²/12
    // per axis, times its orientation), so one particle or a row of them has a rotation as well.
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const uint32_t p : particles) {
        const Eigen::Vector3d d = lattice.state.positionM[p] - fit.centreM;
        covariance += d * (restPlaceM(lattice, p) - restCentre).transpose() + cubeMoment * lattice.state.orientation[p].toRotationMatrix();
        fit.angularMomentumKgM2S += d.cross(m * (lattice.state.velocityMS[p] - fit.velocityMS)) + lattice.model().particleInertiaKgM2 * lattice.state.angularVelocityRadS[p];
        fit.kineticEnergyJ += 0.5 * m * lattice.state.velocityMS[p].squaredNorm() + 0.5 * lattice.model().particleInertiaKgM2 * lattice.state.angularVelocityRadS[p].squaredNorm();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();
    flip(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    fit.rotation = svd.matrixU() * flip * svd.matrixV().transpose();
    // The particles' inertia about their centre, at their rest places in the fitted pose: the
    // points' and each particle's cube's own.
    Eigen::Matrix3d inertiaLocal = n * lattice.model().particleInertiaKgM2 * Eigen::Matrix3d::Identity();
    for (const uint32_t p : particles) {
        const Eigen::Vector3d r = restPlaceM(lattice, p) - restCentre;
        inertiaLocal += m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    }
    fit.angularVelocityRadS = angularVelocityOf(fit.angularMomentumKgM2S, inertiaLocal, fit.rotation);
    return fit;
}

void followLattice(Body& body, const Lattice& lattice)
{
    if (body.anchored && lattice.heldBySupport()) return;
    std::vector<uint32_t> voxels(lattice.model().voxelParticleCount);
    std::iota(voxels.begin(), voxels.end(), 0u);
    setMotionsFromFit({&body}, fitRigidMotion(lattice, voxels), blockCentreOffsetM(body.voxelSizeM, lattice.model().blocks));
}

void addRigidMomentum(Lattice& lattice, const Eigen::Vector3d& linearKgMS, const Eigen::Vector3d& angularAboutOriginKgM2S)
{
    const Lattice::FreeMass free = lattice.freeMass();
    if (free.massKg == 0.0) return;
    // L about the origin = c × P + I ω about the centre, for the rigid field's increment.
    const Eigen::Vector3d dv = linearKgMS / free.massKg;
    const Eigen::Vector3d dw = free.inertiaKgM2.ldlt().solve(angularAboutOriginKgM2S - free.centreM.cross(linearKgMS));
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        if (lattice.model().held[p]) continue;
        lattice.state.velocityMS[p] += dv + dw.cross(lattice.state.positionM[p] - free.centreM);
        lattice.state.angularVelocityRadS[p] += dw;
    }
}

namespace {

/// Each piece's strain energy: its bonds' and its particles' volumetric terms. A broken bond
/// between two pieces holds only contact: its energy belongs to neither.
std::vector<double> pieceStrainEnergiesJ(const Lattice& lattice, const std::vector<uint32_t>& pieceOf, size_t pieceCount)
{
    std::vector<double> strainJ(pieceCount, 0.0);
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (pieceOf[lattice.model().bonds[b].low] == pieceOf[lattice.model().bonds[b].high])
            strainJ[pieceOf[lattice.model().bonds[b].low]] += lattice.bondStrainEnergyJ(b);
    for (uint32_t p = 0; p < lattice.particleCount(); ++p) strainJ[pieceOf[p]] += lattice.volumetricEnergyJ(p);
    return strainJ;
}

}  // namespace

LatticePieces latticePieces(const Lattice& lattice)
{
    LatticePieces pieces;
    DisjointSets sets = lattice.intactPieces();
    std::vector<int32_t> pieceOfRoot(lattice.particleCount(), -1);
    pieces.pieceOf.resize(lattice.particleCount());
    for (uint32_t p = 0; p < lattice.particleCount(); ++p) {
        int32_t& piece = pieceOfRoot[sets.root(p)];
        if (piece < 0) {
            piece = int32_t(pieces.particles.size());
            pieces.particles.emplace_back();
            pieces.held.push_back(0);
            pieces.voxels.push_back(0);
        }
        pieces.pieceOf[p] = uint32_t(piece);
        pieces.particles[size_t(piece)].push_back(p);
        pieces.held[size_t(piece)] |= lattice.model().held[p];
        pieces.voxels[size_t(piece)] += p < lattice.model().voxelParticleCount;
    }
    pieces.vibrationJ = pieceStrainEnergiesJ(lattice, pieces.pieceOf, pieces.particles.size());
    const std::vector<float>& settledJ = lattice.model().settledStrainJ;
    for (size_t i = 0; i < pieces.particles.size(); ++i) {
        const RigidFit fit = fitRigidMotion(lattice, pieces.particles[i]);
        if (!pieces.held[i]) {
            pieces.vibrationJ[i] += fit.kineticEnergyJ - rigidKineticEnergyJ(lattice, pieces.particles[i], fit);
            continue;
        }
        // A held piece at rest still holds what its dead loads strain (settleUnderDeadLoads).
        double deadJ = 0.0;
        if (!settledJ.empty())
            for (const uint32_t p : pieces.particles[i]) deadJ += settledJ[p];
        pieces.vibrationJ[i] = std::max(0.0, pieces.vibrationJ[i] - deadJ) + fit.kineticEnergyJ;
    }
    return pieces;
}

double vibrationEnergyJ(const Lattice& lattice)
{
    const LatticePieces pieces = latticePieces(lattice);
    return std::accumulate(pieces.vibrationJ.begin(), pieces.vibrationJ.end(), 0.0);
}

double elasticCapacityPerVoxelJ(const Material& material, double voxelSizeM)
{
    return material.tensileStrengthPa * material.tensileStrengthPa / (2.0 * material.youngsModulusPa) * voxelSizeM * voxelSizeM * voxelSizeM;
}

DeformableBody continueDeformable(const Body& part, const DeformableBody& whole, const Material& material, const LatticeSettings& settings,
                                  const StaticWorld& supports, uint64_t seed)
{
    DeformableBody d = latticeInBlocks(part, whole.blocks, material, settings, supports, seed, whole.enteredS);
    d.lastLoadedS = whole.lastLoadedS;
    d.awaitedImpactS = whole.awaitedImpactS;
    d.awaitImpactUntilS = whole.awaitImpactUntilS;
    d.coasting = whole.coasting;
    const Lattice& from = whole.lattice;
    Lattice& to = d.lattice;
    // The part's own lattice may hold a voxel by another face than the whole's did (a lone
    // corner voxel has more free faces): a support point the whole lacked, or where the whole
    // had a voxel, and its bond, start afresh.
    const auto counterpart = [&](size_t p) {
        const int32_t q = from.particleAt(to.model().voxel[p]);
        const bool sameKind = q >= 0 && (size_t(q) < from.model().voxelParticleCount) == (p < to.model().voxelParticleCount);
        return sameKind ? q : -1;
    };
    for (size_t p = 0; p < to.particleCount(); ++p) {
        const int32_t q = counterpart(p);
        if (q < 0) continue;
        to.state.positionM[p] = from.state.positionM[size_t(q)];
        to.state.velocityMS[p] = from.state.velocityMS[size_t(q)];
        to.state.angularVelocityRadS[p] = from.state.angularVelocityRadS[size_t(q)];
        to.state.orientation[p] = from.state.orientation[size_t(q)];
    }
    for (size_t b = 0; b < to.bondCount(); ++b) {
        const int32_t low = counterpart(to.model().bonds[b].low), high = counterpart(to.model().bonds[b].high);
        if (low < 0 || high < 0) continue;
        const int32_t c = from.bondAcross(size_t(low), 2 * to.model().bonds[b].axis + 1);
        if (c >= 0) to.state.bondHistory[b] = from.state.bondHistory[size_t(c)];
    }
    // The forces of the part's own bonds; those of bonds to the pieces that left (broken, in
    // contact at most) are gone with them.
    to.refreshForces();
    return d;
}

/// The damage of the bonds that survive (`broken`: per bond, whether it is broken at hand-off),
/// on the links and anchors of the voxels they join (Body::linkDamage); null when none is damaged.
LinkDamageGrid::Ptr survivingDamage(const Body& body, const Lattice& lattice, const std::vector<char>& broken)
{
    const auto survivesDamaged = [&](size_t b) { return !broken[b] && lattice.bondDamage(b) > 0.0; };
    size_t b = 0;
    while (b < lattice.bondCount() && !survivesDamaged(b)) ++b;
    if (b == lattice.bondCount()) return nullptr;
    auto grid = LinkDamageGrid::create(openvdb::Vec4s(0.0f));
    grid->setTransform(body.grid->transform().copy());
    copyActiveTopology(grid->tree(), body.grid->constTree(), openvdb::Vec4s(0.0f));
    auto values = grid->getAccessor();
    const auto links = body.grid->getConstAccessor();
    for (; b < lattice.bondCount(); ++b) {
        if (!survivesDamaged(b)) continue;
        const LatticeBond& bond = lattice.model().bonds[b];
        const bool anchor = std::max(bond.low, bond.high) >= lattice.model().voxelParticleCount;
        const int face = anchor ? -1 : 2 * bond.axis + 1, component = anchor ? kAnchorDamage : bond.axis;
        const int32_t needs = anchor ? kAnchorBit : 1 << face;
        const float damage = float(std::min(lattice.bondDamage(b), kLargestIntactDamage));
        forEachCellOfBlock(lattice.model().voxel[std::min(bond.low, bond.high)], lattice.model().blocks, face, [&](const openvdb::Coord& v) {
            if (!links.isValueOn(v) || !(links.getValue(v) & needs)) return;
            openvdb::Vec4s value = values.getValue(v);
            value[component] = damage;
            values.setValueOn(v, value);
        });
    }
    return grid;
}

HandOff handOff(const Body& body, const Lattice& lattice)
{
    HandOff result;
    Body whole = body;
    whole.grid = body.grid->deepCopy();
    auto links = whole.grid->getAccessor();
    std::vector<char> broken(lattice.bondCount());
    for (size_t b = 0; b < lattice.bondCount(); ++b) broken[b] = lattice.brokenAtHandOff(b);
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        if (!broken[b]) continue;
        const LatticeBond& bond = lattice.model().bonds[b];
        if (std::max(bond.low, bond.high) >= lattice.model().voxelParticleCount) {
            // An anchor: its voxels let go of their support.
            forEachCellOfBlock(lattice.model().voxel[std::min(bond.low, bond.high)], lattice.model().blocks, -1, [&](const openvdb::Coord& v) {
                if (links.isValueOn(v)) links.setValueOn(v, links.getValue(v) & ~kAnchorBit);
            });
            ++result.brokenAnchors;
            continue;
        }
        const int64_t linksBefore = result.brokenLinks;
        forEachCellOfBlock(lattice.model().voxel[bond.low], lattice.model().blocks, 2 * bond.axis + 1, [&](const openvdb::Coord& v) {
            result.brokenLinks += links.isValueOn(v) && breakLink(links, v, 2 * bond.axis + 1) ? 1 : 0;
        });
        result.brokenBonds += result.brokenLinks > linksBefore ? 1 : 0;
    }
    whole.linkDamage = survivingDamage(whole, lattice, broken);
    refreshDerivedData(whole);
    result.parts = splitBody(whole);
    if (result.parts.empty()) result.parts.push_back(std::move(whole));
    // A fragment keeps its parent's index space: its voxels name their particles. Parts of one
    // piece of the lattice (a block's voxels need not touch each other) share its motion.
    DisjointSets pieces(lattice.particleCount());
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (!broken[b]) pieces.join(lattice.model().bonds[b].low, lattice.model().bonds[b].high);
    std::map<uint32_t, std::vector<Body*>> partsOfPiece;
    for (Body& part : result.parts) {
        part.motion.asleep = false;
        part.motion.restTimeS = 0.0;
        if (part.anchored)
            part.motion.linearVelocityMS = part.motion.angularVelocityRadS = Eigen::Vector3d::Zero();
        else
            partsOfPiece[pieces.root(particleOfVoxel(lattice, part.grid->cbeginValueOn().getCoord()))].push_back(&part);
    }
    for (const auto& [root, parts] : partsOfPiece) {
        std::vector<uint32_t> particles;
        for (const Body* part : parts)
            for (auto it = part->grid->constTree().cbeginValueOn(); it; ++it) particles.push_back(particleOfVoxel(lattice, it.getCoord()));
        std::sort(particles.begin(), particles.end());
        particles.erase(std::unique(particles.begin(), particles.end()), particles.end());
        setMotionsFromFit(parts, fitRigidMotion(lattice, particles), blockCentreOffsetM(body.voxelSizeM, lattice.model().blocks));
    }
    return result;
}

namespace {

/// The voxel particles of a part (of its body's lattice, particleOfVoxel), each once.
std::vector<uint32_t> particlesOfPart(const Lattice& lattice, const Body& part)
{
    std::vector<uint32_t> particles;
    for (auto it = part.grid->constTree().cbeginValueOn(); it; ++it) particles.push_back(particleOfVoxel(lattice, it.getCoord()));
    std::sort(particles.begin(), particles.end());
    particles.erase(std::unique(particles.begin(), particles.end()), particles.end());
    return particles;
}

}  // namespace

void nameParts(DeformableBody& deformable, std::vector<Body>& parts, int64_t* nextId)
{
    std::vector<std::vector<uint32_t>> particles;
    for (const Body& part : parts) particles.push_back(particlesOfPart(deformable.lattice, part));
    // Bonds only break, so a part lies within one piece shown; it is that piece when it holds all
    // of the piece's particles.
    const std::vector<int64_t>& shown = deformable.shownIdOfParticle;
    std::map<int64_t, size_t> shownSize;
    for (const int64_t id : shown) ++shownSize[id];
    for (size_t k = 0; k < parts.size(); ++k) {
        parts[k].id = kNoBodyId;
        if (shown.empty() || particles[k].empty()) continue;
        const int64_t id = shown[particles[k].front()];
        const bool whole = std::all_of(particles[k].begin(), particles[k].end(), [&](uint32_t p) { return shown[p] == id; }) &&
                           particles[k].size() == shownSize[id];
        if (id != kNoBodyId && whole) parts[k].id = id;
    }
    if (!nextId) return;
    deformable.shownIdOfParticle.assign(deformable.lattice.model().voxelParticleCount, kNoBodyId);
    for (size_t k = 0; k < parts.size(); ++k) {
        if (parts[k].id == kNoBodyId) parts[k].id = (*nextId)++;
        for (const uint32_t p : particles[k]) deformable.shownIdOfParticle[p] = parts[k].id;
    }
}

bool anyBondBrokenAtHandOff(const Lattice& lattice)
{
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (lattice.brokenAtHandOff(b)) return true;
    return false;
}

Departure leaveQuietPieces(const Body& body, const Lattice& lattice, double tolerancePerParticleJ, bool timeUp)
{
    Departure departure;
    const LatticePieces pieces = latticePieces(lattice);
    std::vector<char> quiet(pieces.particles.size());
    bool freeAndQuiet = false;
    for (size_t k = 0; k < quiet.size(); ++k) {
        quiet[k] = pieces.vibrationJ[k] <= tolerancePerParticleJ * double(pieces.voxels[k]);
        freeAndQuiet = freeAndQuiet || (quiet[k] && !pieces.held[k]);
    }
    const bool allQuiet = std::all_of(quiet.begin(), quiet.end(), [](char q) { return q != 0; });
    if (!timeUp && !allQuiet && !freeAndQuiet) return departure;
    const bool all = timeUp || allQuiet;
    departure.timedOut = timeUp && !allQuiet;
    departure.handOff = handOff(body, lattice);
    for (Body& part : departure.handOff.parts) {
        // A part is a piece, or pieces joined through a support: its first voxel says which.
        const uint32_t piece = pieces.pieceOf[particleOfVoxel(lattice, part.grid->cbeginValueOn().getCoord())];
        part.motion.deformable = !all && !quiet[piece];
    }
    for (size_t k = 0; k < quiet.size(); ++k)
        if (all || quiet[k]) departure.discardedEnergyJ += pieces.vibrationJ[k];
    return departure;
}

bool hasFreePieceAtHandOff(const Lattice& lattice)
{
    DisjointSets sets(lattice.particleCount());
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (!lattice.brokenAtHandOff(b)) sets.join(lattice.model().bonds[b].low, lattice.model().bonds[b].high);
    // Pieces of voxels: a support point left alone is no piece.
    std::vector<char> held(lattice.particleCount(), 0), hasVoxel(lattice.particleCount(), 0);
    for (uint32_t p = 0; p < lattice.particleCount(); ++p) {
        const uint32_t root = sets.root(p);
        hasVoxel[root] |= p < lattice.model().voxelParticleCount;
        held[root] |= lattice.model().held[p];
    }
    int64_t pieces = 0;
    bool anyFree = false;
    for (uint32_t p = 0; p < lattice.particleCount(); ++p) {
        pieces += hasVoxel[p];
        anyFree = anyFree || (hasVoxel[p] && !held[p]);
    }
    return pieces > 1 && anyFree;
}

Departure separateFreePieces(const Body& body, const Lattice& lattice)
{
    Departure departure;
    departure.handOff = handOff(body, lattice);
    // A lone voxel has no bond to strain: leaving rigid, it discards nothing.
    for (Body& part : departure.handOff.parts) part.motion.deformable = part.linkCount > 0 || part.anchored;
    return departure;
}

}  // namespace spall
