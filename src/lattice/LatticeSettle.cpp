// A lattice entering the phase already carrying its dead loads (issue 47): its own weight and
// what its supports bear on it, taken down column by column to the supports (the load takedown of
// masonry design), each bond along the columns compressed by what it carries. Without it a body
// entered stress-free and sagged and rang under gravity switched on at once (the base of a 2.4 m
// brick wall swung through 45 kPa, 15 % of its joints' strength), and nothing held a house wall
// down.
#include <spall/lattice/Lattice.h>

#include <spall/voxel/LinkBits.h>

#include <algorithm>
#include <map>
#include <numeric>

namespace spall {

namespace {

/// The other particle of a bond.
uint32_t across(const LatticeBond& bond, uint32_t p) { return bond.low == p ? bond.high : bond.low; }

/// x with lower[i] x[i−1] + diagonal[i] x[i] + upper[i] x[i+1] = rhs[i], by Thomas's algorithm
/// (Press et al., Numerical Recipes, 3rd ed., §2.4; stable for the diagonally dominant systems
/// of a column).
std::vector<double> solveTridiagonal(const std::vector<double>& lower, std::vector<double> diagonal, const std::vector<double>& upper,
                                     std::vector<double> rhs)
{
    const size_t n = diagonal.size();
    for (size_t i = 1; i < n; ++i) {
        const double w = lower[i] / diagonal[i - 1];
        diagonal[i] -= w * upper[i - 1];
        rhs[i] -= w * rhs[i - 1];
    }
    std::vector<double> x(n);
    for (size_t i = n; i-- > 0;) x[i] = (rhs[i] - (i + 1 < n ? upper[i] * x[i + 1] : 0.0)) / diagonal[i];
    return x;
}

}  // namespace

void Lattice::recordBearingLoad(size_t supportBond, int face, double pressurePa, double friction, const Eigen::Quaterniond& bodyToWorld)
{
    if (pressurePa <= 0.0) return;
    // Into the body across the held face, over the particle's face.
    const Eigen::Vector3d forceN = bodyToWorld * (-faceNormal(face)) * pressurePa * mModel.spacingM * mModel.spacingM;
    mModel.bearingLoads.push_back({uint32_t(supportBond), forceN, friction});
}

bool Lattice::settleUnderDeadLoads(const Eigen::Vector3d& weightPerParticleN)
{
    if (weightPerParticleN.isZero() && mModel.bearingLoads.empty()) return false;
    // Only what stands on a support carries anything.
    if (std::none_of(mModel.held.begin(), mModel.held.end(), [](uint8_t held) { return held != 0; })) return false;
    const Eigen::Quaterniond bodyToWorld = state.orientation.front();  // every particle's, on entry
    const Eigen::Vector3d downInBody = bodyToWorld.inverse() * (weightPerParticleN.isZero() ? -bearingDirection() : weightPerParticleN);
    int axis = 0;
    downInBody.cwiseAbs().maxCoeff(&axis);
    const int sign = downInBody[axis] > 0.0 ? 1 : -1;
    const Eigen::Vector3d downWorld = bodyToWorld * (double(sign) * Eigen::Vector3d::Unit(axis));
    const ColumnLoads columns = takeDownLoads(axis, sign, deadLoadsAlong(weightPerParticleN, downWorld));
    const std::vector<Eigen::Vector3d> moveInBodyM = settlingMoves(axis, sign, columns);
    for (size_t p = 0; p < particleCount(); ++p) state.positionM[p] += bodyToWorld * moveInBodyM[p];
    return true;
}

std::vector<Eigen::Vector3d> Lattice::settlingMoves(int axis, int sign, const ColumnLoads& columns) const
{
    // Each layer's sides move out from its centre (the mean place of its loaded particles).
    std::map<int, std::pair<Eigen::Vector3d, int>> layers;
    for (size_t p = 0; p < mModel.voxelParticleCount; ++p) {
        if (columns.lateralStrain[p] == 0.0) continue;
        auto& [sum, count] = layers.try_emplace(mModel.voxel[p][axis], Eigen::Vector3d::Zero(), 0).first->second;
        sum += Eigen::Vector3d(mModel.voxel[p].x(), mModel.voxel[p].y(), mModel.voxel[p].z());
        ++count;
    }
    const Eigen::Vector3d down = double(sign) * Eigen::Vector3d::Unit(axis);
    std::vector<Eigen::Vector3d> moveM(particleCount(), Eigen::Vector3d::Zero());
    for (size_t p = 0; p < mModel.voxelParticleCount; ++p) {
        moveM[p] = columns.shorteningM[p] * down;
        if (columns.lateralStrain[p] == 0.0) continue;
        const auto& [sum, count] = layers.at(mModel.voxel[p][axis]);
        Eigen::Vector3d fromCentre = Eigen::Vector3d(mModel.voxel[p].x(), mModel.voxel[p].y(), mModel.voxel[p].z()) - sum / count;
        fromCentre[axis] = 0.0;
        moveM[p] += columns.lateralStrain[p] * mModel.spacingM * fromCentre;
    }
    // A support moves with its voxel, so its bond starts unstrained, except along the columns:
    // one below stays, bearing its column; one above was placed with its column.
    const int faceBelow = 2 * axis + (sign > 0 ? 1 : 0);
    for (size_t p = mModel.voxelParticleCount; p < particleCount(); ++p)
        for (int face = 0; face < kFaceCount; ++face) {
            const int32_t b = mModel.bondAcross[p][face];
            if (b < 0 || face == (faceBelow ^ 1)) continue;
            moveM[p] = moveM[across(mModel.bonds[size_t(b)], uint32_t(p))];
            if (face == faceBelow) moveM[p][axis] = columns.shorteningM[p] * sign;
        }
    return moveM;
}

Eigen::Vector3d Lattice::bearingDirection() const
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const LatticeModel::BearingLoad& load : mModel.bearingLoads) sum += load.forceN;
    return sum.normalized();
}

std::vector<double> Lattice::deadLoadsAlong(const Eigen::Vector3d& weightPerParticleN, const Eigen::Vector3d& downWorld) const
{
    std::vector<double> loadN(particleCount(), 0.0);
    for (size_t p = 0; p < mModel.voxelParticleCount; ++p) loadN[p] = mModel.held[p] ? 0.0 : weightPerParticleN.dot(downWorld);
    // A support's bearing only where it pushes along the columns (a floor on a wall's head).
    for (const LatticeModel::BearingLoad& load : mModel.bearingLoads) {
        const LatticeBond& bond = mModel.bonds[load.bond];
        loadN[std::min(bond.low, bond.high)] += std::max(0.0, load.forceN.dot(downWorld));
    }
    return loadN;
}

Lattice::ColumnLoads Lattice::takeDownLoads(int axis, int sign, const std::vector<double>& loadN) const
{
    // The bond below a particle is across its face that looks down.
    const int faceBelow = 2 * axis + (sign > 0 ? 1 : 0);
    const auto bondBelow = [&](uint32_t p) {
        const int32_t b = mModel.bondAcross[p][faceBelow];
        return b >= 0 && !mModel.bonds[size_t(b)].pinned && bondDamage(size_t(b)) < 1.0 ? b : -1;
    };
    // Top first: the coordinate along the axis, against the way down.
    std::vector<uint32_t> topFirst(particleCount());
    std::iota(topFirst.begin(), topFirst.end(), 0u);
    std::stable_sort(topFirst.begin(), topFirst.end(), [&](uint32_t a, uint32_t b) { return sign * mModel.voxel[a][axis] < sign * mModel.voxel[b][axis]; });
    // A column carries only where it stands on a support, unbroken: a particle over a gap (a
    // lintel over an opening) would need its load carried sideways, which a column cannot.
    std::vector<uint8_t> standsOnSupport(particleCount(), 0);
    for (auto it = topFirst.rbegin(); it != topFirst.rend(); ++it) {
        const int32_t b = bondBelow(*it);
        standsOnSupport[*it] = mModel.held[*it] || (b >= 0 && standsOnSupport[across(mModel.bonds[size_t(b)], *it)]);
    }
    ColumnLoads columns;
    columns.carriedN.assign(particleCount(), 0.0);
    for (const uint32_t p : topFirst) {
        if (!standsOnSupport[p] || mModel.held[p]) continue;
        columns.carriedN[p] += loadN[p];
        columns.carriedN[across(mModel.bonds[size_t(bondBelow(p))], p)] += columns.carriedN[p];
    }
    // Each column's bonds shorten so that the lattice's own forces carry what they must.
    columns.shorteningM.assign(particleCount(), 0.0);
    columns.lateralStrain.assign(particleCount(), 0.0);
    const int faceAbove = faceBelow ^ 1;
    for (const uint32_t top : topFirst) {
        if (!standsOnSupport[top] || mModel.held[top]) continue;
        const int32_t above = mModel.bondAcross[top][faceAbove];
        const uint32_t upper = above >= 0 ? across(mModel.bonds[size_t(above)], top) : top;
        if (above >= 0 && !mModel.held[upper] && bondBelow(upper) == above) continue;  // not a column's top
        shortenColumn(top, axis, faceBelow, columns);
    }
    return columns;
}

int Lattice::lateralAxesWithBonds(uint32_t p, int axis) const
{
    int count = 0;
    for (int b = 0; b < 3; ++b) count += b != axis && mModel.inverseBondCount[p][b] > 0.0;
    return count;
}

double Lattice::lateralPoissonRatio(uint32_t p, int axis) const
{
    // Uniaxial stress along the axis: each lateral axis with bonds is free of stress,
    // d ε_lat + λ tr ε = 0 with tr ε = ε_axis + m ε_lat over the m lateral axes with bonds, so
    // ε_lat = −λ / (d + m λ) ε_axis (isotropic in the bulk: λ / (2μ + 2λ) = ν), d the mean of
    // those axes' moduli.
    const int lateralAxes = lateralAxesWithBonds(p, axis);
    if (lateralAxes == 0) return 0.0;
    double modulusPa = 0.0;
    for (int b = 0; b < 3; ++b)
        if (b != axis && mModel.inverseBondCount[p][b] > 0.0) modulusPa += mModel.stiffness.normalModulusPa[size_t(b)];
    const double lambda = mModel.lambdaPa[p];
    return lambda / (modulusPa / lateralAxes + lateralAxes * lambda);
}

void Lattice::shortenColumn(uint32_t top, int axis, int faceBelow, ColumnLoads& columns) const
{
    // The column from its top down to the support it stands on: particles p0 … pm (pm held),
    // bond i between p_i and p_(i+1) carrying F_i and shortening by δ_i, its particles' sides
    // free to spread as uniaxial stress spreads them (lateralPoissonRatio: tr ε is then
    // (1 − m ν) times the strain along the axis). A bond's force is its spring's, k δ_i, and the
    // volumetric term's (completeBondForce), h Σ over its two ends of λ_p (1 − m ν_p) / n_p²
    // times the shortenings of p's bonds along the axis (their mean over h is p's strain along
    // it, and each bond takes 1/n of λ tr ε): a tridiagonal system. A support above the column
    // carries none of it (its bearing acts as a force): its bond is one more unknown, carrying
    // nothing, and the support is placed where that leaves it.
    std::vector<uint32_t> particles{top};
    std::vector<size_t> bonds;
    const int32_t above = mModel.bondAcross[top][faceBelow ^ 1];
    if (above >= 0 && !mModel.bonds[size_t(above)].pinned && mModel.held[across(mModel.bonds[size_t(above)], top)]) {
        particles.insert(particles.begin(), across(mModel.bonds[size_t(above)], top));
        bonds.push_back(size_t(above));
    }
    while (!mModel.held[particles.back()]) {
        const size_t b = size_t(mModel.bondAcross[particles.back()][faceBelow]);
        bonds.push_back(b);
        particles.push_back(across(mModel.bonds[b], particles.back()));
    }
    const size_t n = bonds.size();
    const double h = mModel.spacingM;
    const auto volumetricPerM = [&](uint32_t p) {
        const double spread = 1.0 - lateralAxesWithBonds(p, axis) * lateralPoissonRatio(p, axis);
        return h * mModel.lambdaPa[p] * spread * mModel.inverseBondCount[p][axis] * mModel.inverseBondCount[p][axis];
    };
    std::vector<double> lower(n, 0.0), diagonal(n), upper(n, 0.0), rhs(n);
    for (size_t i = 0; i < n; ++i) {
        const double above = volumetricPerM(particles[i]), below = volumetricPerM(particles[i + 1]);
        diagonal[i] = mModel.stiffness.normalNPerM[size_t(axis)] + above + below;
        if (i > 0) lower[i] = above;
        if (i + 1 < n) upper[i] = below;
        rhs[i] = mModel.held[particles[i]] ? 0.0 : columns.carriedN[particles[i]];
    }
    const std::vector<double> shorteningM = solveTridiagonal(lower, diagonal, upper, rhs);
    double downM = 0.0;
    for (size_t i = n; i-- > 0;) {
        downM += shorteningM[i];
        columns.shorteningM[particles[i]] = downM;
    }
    for (size_t i = 0; i < n; ++i) {
        const uint32_t p = particles[i];
        if (mModel.held[p]) continue;
        const double strain = ((i > 0 ? shorteningM[i - 1] : 0.0) + shorteningM[i]) * mModel.inverseBondCount[p][axis] / h;
        columns.lateralStrain[p] = lateralPoissonRatio(p, axis) * strain;
    }
}

void Lattice::recordSettledStrainEnergies()
{
    mModel.settledStrainJ.assign(particleCount(), 0.0f);
    for (size_t b = 0; b < bondCount(); ++b) {
        const float half = float(0.5 * bondStrainEnergyJ(b));
        mModel.settledStrainJ[mModel.bonds[b].low] += half;
        mModel.settledStrainJ[mModel.bonds[b].high] += half;
    }
    for (size_t p = 0; p < particleCount(); ++p) mModel.settledStrainJ[p] += float(volumetricEnergyJ(p));
}

}  // namespace spall
