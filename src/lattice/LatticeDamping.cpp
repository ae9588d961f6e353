// The material's own damping in the deformable phase: each piece's vibration about its rigid
// motion decays as mass-proportional (Rayleigh) damping would make it, at the material's damping
// ratio at the piece's fundamental mode. Mass-proportional damping leaves the stable step as it
// is (stiffness-proportional damping at a wall's 10 Hz would shrink it a thousandfold), and about
// each piece's rigid motion it neither slows a flying piece nor changes any momentum.
#include <spall/lattice/Lattice.h>

#include <spall/core/Parallel.h>

#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace spall {

DisjointSets Lattice::intactPieces() const
{
    DisjointSets sets(particleCount());
    for (size_t b = 0; b < bondCount(); ++b)
        if (!isBroken(b)) sets.join(mModel.bonds[b].low, mModel.bonds[b].high);
    return sets;
}

double Lattice::fundamentalFrequencyRadS(double thicknessM, double lengthM, bool isHeld) const
{
    const double barSpeedMS = std::sqrt(mModel.stiffness.strength[0].youngsModulusPa * mModel.spacingM * mModel.spacingM * mModel.spacingM / mModel.particleMassKg);
    // (β L)² / √12 for a rectangular section's radius of gyration t / √12: β L = 4.730 free-free,
    // 1.875 clamped-free (Clough & Penzien §18-3).
    const double shapeFactor = isHeld ? 1.875 * 1.875 / std::sqrt(12.0) : 4.730 * 4.730 / std::sqrt(12.0);
    return shapeFactor * barSpeedMS * thicknessM / (lengthM * lengthM);
}

bool Lattice::heldBySupport() const
{
    return std::any_of(mModel.bondsToHeld.begin(), mModel.bondsToHeld.end(), [&](uint32_t b) { return !isBroken(b); });
}

std::vector<uint32_t> Lattice::bondsFromHeld() const
{
    // Breadth first from every held particle at once, through intact bonds, in particle order.
    constexpr uint32_t kUnreached = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> hops(particleCount(), kUnreached), front;
    for (uint32_t p = 0; p < particleCount(); ++p)
        if (mModel.held[p]) {
            hops[p] = 0;
            front.push_back(p);
        }
    for (size_t next = 0; next < front.size(); ++next) {
        const uint32_t p = front[next];
        for (int face = 0; face < 6; ++face) {
            const int32_t b = mModel.bondAcross[p][face];
            if (b < 0 || isBroken(size_t(b))) continue;
            const uint32_t q = mModel.bonds[size_t(b)].low == p ? mModel.bonds[size_t(b)].high : mModel.bonds[size_t(b)].low;
            if (hops[q] != kUnreached) continue;
            hops[q] = hops[p] + 1;
            front.push_back(q);
        }
    }
    return hops;
}

void Lattice::findDampedPieces()
{
    DisjointSets sets = intactPieces();
    std::vector<int32_t> pieceOfRoot(particleCount(), -1);
    std::vector<openvdb::Coord> low, high;
    std::vector<std::vector<uint32_t>> members;
    std::vector<char> pieceHeld, pieceHeldByVoxels;
    std::vector<uint32_t> pieceReach;  // a held piece's most bonds between a particle and a held one (a free piece's: unreached)
    const std::vector<uint32_t> hops = bondsFromHeld();
    for (uint32_t p = 0; p < particleCount(); ++p) {
        int32_t& piece = pieceOfRoot[sets.root(p)];
        if (piece < 0) {
            piece = int32_t(members.size());
            members.emplace_back();
            pieceHeld.push_back(0);
            pieceHeldByVoxels.push_back(0);
            pieceReach.push_back(0);
            low.push_back(mModel.voxel[p]);
            high.push_back(mModel.voxel[p]);
        }
        members[size_t(piece)].push_back(p);
        pieceHeld[size_t(piece)] |= mModel.held[p];
        pieceHeldByVoxels[size_t(piece)] |= mModel.held[p] && p < mModel.voxelParticleCount;
        pieceReach[size_t(piece)] = std::max(pieceReach[size_t(piece)], hops[p]);
        low[size_t(piece)].minComponent(mModel.voxel[p]);
        high[size_t(piece)].maxComponent(mModel.voxel[p]);
    }
    // Runs of at most kDampingChunk of a piece's particles, in piece and particle order: summed
    // apart in parallel and joined in this order, so the sums do not depend on the threads.
    mDampedPieces.assign(members.size(), DampedPiece());
    mPieceParticles.clear();
    mDampingChunks.clear();
    for (size_t k = 0; k < members.size(); ++k) {
        DampedPiece& piece = mDampedPieces[k];
        piece.held = pieceHeld[k] != 0;
        piece.heldByVoxels = pieceHeldByVoxels[k] != 0;
        std::array<double, 3> sides{};
        for (int axis = 0; axis < 3; ++axis) sides[size_t(axis)] = double(high[k][axis] - low[k][axis] + 1) * mModel.spacingM;
        std::sort(sides.begin(), sides.end());
        const double lengthM = piece.held ? (pieceReach[k] + 0.5) * mModel.spacingM : sides[2];
        piece.decayPerS = 2.0 * mModel.dampingRatio * fundamentalFrequencyRadS(sides[0], lengthM, piece.held);
        piece.firstParticle = members[k].front();
        piece.firstMember = uint32_t(mPieceParticles.size());
        piece.endMember = uint32_t(mPieceParticles.size() + members[k].size());
        // A cantilever of height H and thickness t under a uniform load reaches ft at its base
        // with its tip deflected ft H² / (2 E t) (Euler–Bernoulli): a chord turned by ε_t H / (2t),
        // a best-fit (least-squares) turn of (8/15) ε_t H / t. 2 ε_t H / t, 3.75 times that, is
        // past anything its support holds elastically (2.9 times under a load at its tip).
        piece.hingeRotationRad = 2.0 * (mModel.stiffness.strength[0].peakStretchM / mModel.spacingM) * lengthM / sides[0];
        for (size_t begin = 0; begin < members[k].size(); begin += kDampingChunk) {
            const uint32_t start = uint32_t(mPieceParticles.size() + begin);
            mDampingChunks.push_back({uint32_t(k), start, start + uint32_t(std::min(kDampingChunk, members[k].size() - begin))});
        }
        mPieceParticles.insert(mPieceParticles.end(), members[k].begin(), members[k].end());
    }
    findSupportBondsOfPieces(pieceOfRoot, sets);
    mPiecesStale = false;
}

void Lattice::findSupportBondsOfPieces(const std::vector<int32_t>& pieceOfRoot, DisjointSets& sets)
{
    std::vector<std::vector<uint32_t>> supportBonds(mDampedPieces.size());
    for (size_t b = 0; b < bondCount(); ++b) {
        const LatticeBond& bond = mModel.bonds[b];
        if (std::max(bond.low, bond.high) < mModel.voxelParticleCount || isBroken(b)) continue;
        supportBonds[size_t(pieceOfRoot[sets.root(std::min(bond.low, bond.high))])].push_back(uint32_t(b));
    }
    mPieceSupportBonds.clear();
    for (size_t k = 0; k < mDampedPieces.size(); ++k) {
        mDampedPieces[k].firstSupportBond = uint32_t(mPieceSupportBonds.size());
        mPieceSupportBonds.insert(mPieceSupportBonds.end(), supportBonds[k].begin(), supportBonds[k].end());
        mDampedPieces[k].endSupportBond = uint32_t(mPieceSupportBonds.size());
    }
}

bool Lattice::turnedPastHinge(const DampedPiece& piece) const
{
    // Kabsch (1976): the rotation from the particles' rest places (turned as the body was at
    // rest) to where they are, about their centres; places taken from the first particle. A
    // thousand particles evenly through the piece fix a rotation as well as all of them do for
    // a threshold, at a cost that does not grow with the piece.
    const uint32_t stride = std::max<uint32_t>(1, (piece.endMember - piece.firstMember) / 1024);
    const Eigen::Matrix3d restTurn = mModel.restOrientation.toRotationMatrix();
    const Eigen::Vector3d originM = state.positionM[piece.firstParticle];
    const openvdb::Coord& originVoxel = mModel.voxel[piece.firstParticle];
    Eigen::Vector3d sumPlaceM = Eigen::Vector3d::Zero(), sumRestM = Eigen::Vector3d::Zero();
    Eigen::Matrix3d sumPlaceRestM2 = Eigen::Matrix3d::Zero();
    double n = 0.0;
    for (uint32_t i = piece.firstMember; i < piece.endMember; i += stride) {
        const uint32_t p = mPieceParticles[i];
        if (mModel.held[p]) continue;
        const openvdb::Coord d = mModel.voxel[p] - originVoxel;
        const Eigen::Vector3d rest = restTurn * (mModel.spacingM * Eigen::Vector3d(d.x(), d.y(), d.z()));
        const Eigen::Vector3d place = state.positionM[p] - originM;
        sumPlaceM += place;
        sumRestM += rest;
        sumPlaceRestM2 += place * rest.transpose();
        n += 1.0;
    }
    if (n < 3.0) return false;
    const Eigen::Matrix3d covariance = sumPlaceRestM2 - sumPlaceM * sumRestM.transpose() / n;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
    // Particles on one line fix no turn about it: the fit's would be rounding noise.
    if (svd.singularValues()(1) <= 1e-9 * svd.singularValues()(0)) return false;
    Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();
    flip(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    const Eigen::Matrix3d turn = svd.matrixU() * flip * svd.matrixV().transpose();
    return Eigen::AngleAxisd(turn).angle() > piece.hingeRotationRad;
}

bool Lattice::openSupportHinges()
{
    if (mPiecesStale) findDampedPieces();
    bool opened = false;
    for (const DampedPiece& piece : mDampedPieces) {
        // A piece held by its own voxels (no free face to a support) stays held whatever its
        // support bonds do: breaking them would free nothing.
        if (!piece.held || piece.heldByVoxels) continue;
        const auto first = mPieceSupportBonds.begin() + piece.firstSupportBond, end = mPieceSupportBonds.begin() + piece.endSupportBond;
        // An uncracked support holds elastically: nothing to measure.
        if (std::none_of(first, end, [&](uint32_t b) { return bondDamage(b) > 0.0; }) || !turnedPastHinge(piece)) continue;
        for (auto b = first; b != end; ++b) breakBond(*b);
        opened = true;
    }
    return opened;
}

namespace {

/// Chunks a task takes: most pieces are a few particles, a chunk of a large one is thousands.
constexpr size_t kChunksPerTask = 4;

/// A free piece's particles' sums, places taken from its first particle (so that a small piece
/// far from the origin keeps its inertia's digits).
struct PieceSums {
    double massKg = 0.0;
    double particles = 0.0;
    Eigen::Vector3d momentumKgMS = Eigen::Vector3d::Zero();
    Eigen::Vector3d firstMomentKgM = Eigen::Vector3d::Zero();
    Eigen::Matrix3d secondMomentKgM2 = Eigen::Matrix3d::Zero();
    Eigen::Vector3d angularMomentumKgM2S = Eigen::Vector3d::Zero();  ///< about the piece's first particle, spins included

    void add(const PieceSums& o)
    {
        massKg += o.massKg;
        particles += o.particles;
        momentumKgMS += o.momentumKgMS;
        firstMomentKgM += o.firstMomentKgM;
        secondMomentKgM2 += o.secondMomentKgM2;
        angularMomentumKgM2S += o.angularMomentumKgM2S;
    }
};

/// The rigid motion with a piece's momenta: its centre (from its first particle), velocity and
/// spin.
struct PieceMotion {
    Eigen::Vector3d centreM = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocityMS = Eigen::Vector3d::Zero();
    Eigen::Vector3d spinRadS = Eigen::Vector3d::Zero();
};

PieceMotion rigidMotionOf(const PieceSums& sums, double particleInertiaKgM2)
{
    PieceMotion motion;
    motion.centreM = sums.firstMomentKgM / sums.massKg;
    motion.velocityMS = sums.momentumKgMS / sums.massKg;
    const Eigen::Vector3d angularAboutCentre = sums.angularMomentumKgM2S - motion.centreM.cross(sums.momentumKgMS);
    const Eigen::Matrix3d spread = sums.secondMomentKgM2 - sums.massKg * motion.centreM * motion.centreM.transpose();
    const Eigen::Matrix3d inertia = (spread.trace() + sums.particles * particleInertiaKgM2) * Eigen::Matrix3d::Identity() - spread;
    motion.spinRadS = inertia.ldlt().solve(angularAboutCentre);
    return motion;
}

}  // namespace

void Lattice::dampVibration(double dtS)
{
    if (mModel.dampingRatio <= 0.0) return;
    if (mPiecesStale) findDampedPieces();
    // Each chunk of a free piece summed in parallel, the chunks joined per piece in order.
    std::vector<PieceSums> chunkSums(mDampingChunks.size());
    forEachIndex(
        mDampingChunks.size(),
        [&](size_t c) {
            const DampingChunk& chunk = mDampingChunks[c];
            const DampedPiece& piece = mDampedPieces[chunk.piece];
            if (piece.held) return;
            PieceSums& s = chunkSums[c];
            for (uint32_t i = chunk.begin; i < chunk.end; ++i) {
                const uint32_t p = mPieceParticles[i];
                const Eigen::Vector3d r = state.positionM[p] - state.positionM[piece.firstParticle];
                s.massKg += mModel.particleMassKg;
                s.particles += 1.0;
                s.momentumKgMS += mModel.particleMassKg * state.velocityMS[p];
                s.firstMomentKgM += mModel.particleMassKg * r;
                s.secondMomentKgM2 += mModel.particleMassKg * r * r.transpose();
                s.angularMomentumKgM2S += r.cross(mModel.particleMassKg * state.velocityMS[p]) + mModel.particleInertiaKgM2 * state.angularVelocityRadS[p];
            }
        },
        kChunksPerTask);
    std::vector<PieceSums> sums(mDampedPieces.size());
    for (size_t c = 0; c < mDampingChunks.size(); ++c) sums[mDampingChunks[c].piece].add(chunkSums[c]);
    // A held piece's rigid motion is rest.
    std::vector<PieceMotion> motion(mDampedPieces.size());
    for (size_t k = 0; k < mDampedPieces.size(); ++k)
        if (!mDampedPieces[k].held) motion[k] = rigidMotionOf(sums[k], mModel.particleInertiaKgM2);
    forEachIndex(
        mDampingChunks.size(),
        [&](size_t c) {
            const DampingChunk& chunk = mDampingChunks[c];
            const DampedPiece& piece = mDampedPieces[chunk.piece];
            const PieceMotion& m = motion[chunk.piece];
            const double keep = std::exp(-piece.decayPerS * dtS);
            const Eigen::Vector3d originM = state.positionM[piece.firstParticle];
            for (uint32_t i = chunk.begin; i < chunk.end; ++i) {
                const uint32_t p = mPieceParticles[i];
                if (mModel.held[p]) continue;
                const Eigen::Vector3d rigidVelocity = m.velocityMS + m.spinRadS.cross(state.positionM[p] - originM - m.centreM);
                state.velocityMS[p] = rigidVelocity + keep * (state.velocityMS[p] - rigidVelocity);
                state.angularVelocityRadS[p] = m.spinRadS + keep * (state.angularVelocityRadS[p] - m.spinRadS);
            }
        },
        kChunksPerTask);
}

}  // namespace spall
