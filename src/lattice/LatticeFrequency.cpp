// The lattice's highest frequency, which sets its stable step (issue 49). A lattice's linearised
// equations of motion, repeated along an axis, have plane-wave (Bloch) solutions: a cell's
// displacements u and turns θ times e^{i θ_a} from one cell to the next along axis a; at each
// phase the cell's dynamical matrix D gives ω² as the eigenvalues of M⁻¹ D (Brillouin, Wave
// Propagation in Periodic Structures, 1946; Ashcroft & Mermin, Solid State Physics, ch. 22).
// The unbounded lattice is a cell of one particle repeated along all three axes. Its surfaces
// can ring faster: a particle on a face has one bond along its normal, whose stretch then counts
// whole in its volumetric strain, not halved, which for λ large against μ (ν above about 1/3)
// lifts a face's or an edge's highest mode above the bulk's (an independent audit, 2026-12-06).
// So faces (slabs a few particles thick, repeated along the other two axes), edges (bars) and
// corners (small cubes) are cells here too, and the highest of all sets the step.
#include <spall/lattice/LatticeModel.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <vector>

namespace spall {

namespace {

using Complex = std::complex<double>;

/// n[0] × n[1] × n[2] particles, repeated along the axes marked periodic and free across the
/// others (there its faces are a body's surface).
struct Cell {
    std::array<int, 3> n{1, 1, 1};
    std::array<bool, 3> periodic{true, true, true};
    int count() const { return n[0] * n[1] * n[2]; }
    int index(const std::array<int, 3>& c) const { return c[0] + n[0] * (c[1] + n[1] * c[2]); }
};

/// One bond of the cell: its low and high particle, axis, and the phase across the cell's
/// boundary (1 inside it).
struct CellBond {
    int low, high, axis;
    Complex phase;
};

std::vector<CellBond> bondsOf(const Cell& cell, const Eigen::Vector3d& cellPhase)
{
    std::vector<CellBond> bonds;
    for (int l = 0; l < cell.n[2]; ++l)
        for (int j = 0; j < cell.n[1]; ++j)
            for (int i = 0; i < cell.n[0]; ++i)
                for (int a = 0; a < 3; ++a) {
                    std::array<int, 3> c{i, j, l};
                    const int low = cell.index(c);
                    Complex phase = 1.0;
                    if (++c[size_t(a)] == cell.n[size_t(a)]) {
                        // A free side has no bond; a cell one particle long along a periodic
                        // axis is bonded to its own image.
                        if (!cell.periodic[size_t(a)]) continue;
                        c[size_t(a)] = 0;
                        phase = std::polar(1.0, cellPhase[a]);
                    }
                    bonds.push_back({low, cell.index(c), a, phase});
                }
    return bonds;
}

/// The skew matrix of e_a × (·).
Eigen::Matrix3d crossWithAxis(int a)
{
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    m(c, b) = 1.0;
    m(b, c) = -1.0;
    return m;
}

/// D of the cell at the phases across it (unit: N/m on u, N m/rad on θ), from its bonds'
/// energy and each particle's volumetric term ½ λ_p h³ (tr ε)², weighted and condensed as
/// Lattice::condenseVolumetricModulus does.
Eigen::MatrixXcd dynamicalMatrix(const LatticeStiffness& k, double h, const Cell& cell, const Eigen::Vector3d& cellPhase)
{
    const int dofs = 6 * cell.count();
    const std::vector<CellBond> bonds = bondsOf(cell, cellPhase);
    Eigen::MatrixXcd d = Eigen::MatrixXcd::Zero(dofs, dofs);
    std::vector<std::array<int, 3>> bondsAlong(size_t(cell.count()), {0, 0, 0});
    // Each particle's stretches, h tr ε = Σ_a w_a Σ (its bonds' stretches along a), as rows.
    std::vector<Eigen::RowVectorXcd> stretches(size_t(cell.count()), Eigen::RowVectorXcd::Zero(dofs));
    std::vector<std::array<Eigen::RowVectorXcd, 3>> stretchAlong(size_t(cell.count()));
    for (auto& rows : stretchAlong) rows.fill(Eigen::RowVectorXcd::Zero(dofs));
    for (const CellBond& bond : bonds) {
        const int a = bond.axis, u0 = 6 * bond.low, u1 = 6 * bond.high;
        // Linearised in the bond's half-way frame: its faces part by d = φ u_high − u_low +
        // (h/2) e_a × (θ_low + φ θ_high), and it turns by φ θ_high − θ_low (Lattice::strainOf).
        Eigen::MatrixXcd strain = Eigen::MatrixXcd::Zero(6, dofs);
        const Eigen::Matrix3cd arm = (0.5 * h) * crossWithAxis(a).cast<Complex>();
        strain.block(0, u1, 3, 3) += bond.phase * Eigen::Matrix3cd::Identity();
        strain.block(0, u0, 3, 3) -= Eigen::Matrix3cd::Identity();
        strain.block(0, u0 + 3, 3, 3) += arm;
        strain.block(0, u1 + 3, 3, 3) += bond.phase * arm;
        strain.block(3, u1 + 3, 3, 3) += bond.phase * Eigen::Matrix3cd::Identity();
        strain.block(3, u0 + 3, 3, 3) -= Eigen::Matrix3cd::Identity();
        Eigen::Matrix<double, 6, 1> springs;
        springs << k.shearNPerM[size_t(a)], Eigen::Vector3d::Constant(k.bendingNmPerRad[size_t(a)]);
        springs[a] = k.normalNPerM[size_t(a)];
        springs[3 + a] = k.twistingNmPerRad[size_t(a)];
        d += strain.adjoint() * springs.cast<Complex>().asDiagonal() * strain;
        // Its stretch, in the low particle's cell and (times φ*) in the high one's.
        stretchAlong[size_t(bond.low)][size_t(a)] += strain.row(a);
        stretchAlong[size_t(bond.high)][size_t(a)] += std::conj(bond.phase) * strain.row(a);
        ++bondsAlong[size_t(bond.low)][size_t(a)];
        ++bondsAlong[size_t(bond.high)][size_t(a)];
    }
    for (size_t p = 0; p < size_t(cell.count()); ++p) {
        Eigen::RowVectorXcd trace = Eigen::RowVectorXcd::Zero(dofs);
        std::array<bool, 3> bondedAlong{};
        for (size_t a = 0; a < 3; ++a) {
            bondedAlong[a] = bondsAlong[p][a] > 0;
            if (bondedAlong[a]) trace += stretchAlong[p][a] / double(bondsAlong[p][a]);
        }
        d += (condensedLambdaPa(k, bondedAlong) * h) * trace.adjoint() * trace;
    }
    return d;
}

/// The cell's largest ω² at the phases across it (unit: rad²/s²).
double highestOmegaSquaredAt(const LatticeStiffness& k, double h, double massKg, const Cell& cell, const Eigen::Vector3d& cellPhase)
{
    const double inertiaKgM2 = massKg * h * h / 6.0;  // a cube's
    Eigen::VectorXcd inverseRootMass(6 * cell.count());
    for (int p = 0; p < cell.count(); ++p)
        inverseRootMass.segment<6>(6 * p) << Eigen::Vector3cd::Constant(1.0 / std::sqrt(massKg)), Eigen::Vector3cd::Constant(1.0 / std::sqrt(inertiaKgM2));
    const Eigen::MatrixXcd scaled = inverseRootMass.asDiagonal() * dynamicalMatrix(k, h, cell, cellPhase) * inverseRootMass.asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(scaled, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
}

/// The cell's highest ω² over its phases: D(−φ) is D(φ)'s conjugate and each axis's reflection
/// leaves the spectrum as it is, so phases in [0, π] along each periodic axis hold every
/// frequency: a grid over them, then a pattern search from its best point (unit: rad²/s²).
double highestOmegaSquaredOf(const LatticeStiffness& k, double h, double massKg, const Cell& cell)
{
    const auto at = [&](const Eigen::Vector3d& phase) { return highestOmegaSquaredAt(k, h, massKg, cell, phase); };
    constexpr int kIntervals = 12;
    const double step = M_PI / kIntervals;
    std::array<int, 3> points{};
    for (size_t a = 0; a < 3; ++a) points[a] = cell.periodic[a] ? kIntervals + 1 : 1;
    Eigen::Vector3d best = Eigen::Vector3d::Zero();
    double bestOmega2 = at(best);
    for (int i = 0; i < points[0]; ++i)
        for (int j = 0; j < points[1]; ++j)
            for (int l = 0; l < points[2]; ++l) {
                const Eigen::Vector3d phase(i * step, j * step, l * step);
                if (const double omega2 = at(phase); omega2 > bestOmega2) bestOmega2 = omega2, best = phase;
            }
    for (double stride = 0.5 * step; stride > 1e-6; stride *= 0.5) {
        bool improved = true;
        while (improved) {
            improved = false;
            for (int axis = 0; axis < 3; ++axis)
                for (const double sign : {-1.0, 1.0}) {
                    if (!cell.periodic[size_t(axis)]) continue;
                    Eigen::Vector3d phase = best;
                    phase[axis] = std::clamp(phase[axis] + sign * stride, 0.0, M_PI);
                    if (const double omega2 = at(phase); omega2 > bestOmega2) bestOmega2 = omega2, best = phase, improved = true;
                }
        }
    }
    return bestOmega2;
}

/// The bulk, and faces, edges and corners up to three particles across along each axis.
double searchHighestFrequencyRadS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg)
{
    double highestOmega2 = highestOmegaSquaredOf(stiffness, spacingM, particleMassKg, Cell{});
    for (int across = 1; across <= 3; ++across)
        for (int a = 0; a < 3; ++a) {
            Cell slab, bar;
            slab.n[size_t(a)] = across;
            slab.periodic[size_t(a)] = false;
            bar.n.fill(across);
            bar.periodic.fill(false);
            bar.n[size_t(a)] = 1;
            bar.periodic[size_t(a)] = true;
            highestOmega2 = std::max({highestOmega2, highestOmegaSquaredOf(stiffness, spacingM, particleMassKg, slab),
                                      highestOmegaSquaredOf(stiffness, spacingM, particleMassKg, bar)});
        }
    for (int across = 2; across <= 3; ++across) {
        Cell cube;
        cube.n.fill(across);
        cube.periodic.fill(false);
        highestOmega2 = std::max(highestOmega2, highestOmegaSquaredOf(stiffness, spacingM, particleMassKg, cube));
    }
    return std::sqrt(highestOmega2);
}

}  // namespace

double highestFrequencyRadS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg)
{
    // A search takes milliseconds and every lattice built asks (an impact's pieces, hundreds a
    // run), of a few materials and sizes: kept by its inputs.
    std::vector<double> key{spacingM, particleMassKg, stiffness.lameLambdaPa};
    for (size_t a = 0; a < 3; ++a) {
        key.insert(key.end(), {stiffness.normalNPerM[a], stiffness.bendingNmPerRad[a], stiffness.twistingNmPerRad[a]});
        key.insert(key.end(), stiffness.shearNPerM[a].data(), stiffness.shearNPerM[a].data() + 3);
    }
    static std::mutex mutex;
    static std::map<std::vector<double>, double> found;
    const std::lock_guard<std::mutex> lock(mutex);
    const auto known = found.find(key);
    return known != found.end() ? known->second : found.emplace(key, searchHighestFrequencyRadS(stiffness, spacingM, particleMassKg)).first->second;
}

double stableTimeStepS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg, double bondDashpotNSPerM)
{
    const double omegaRadS = highestFrequencyRadS(stiffness, spacingM, particleMassKg);
    // Central differences (velocity Verlet) are stable while ω dt < 2 (Belytschko, Liu & Moran,
    // Nonlinear Finite Elements for Continua and Structures, 2000, ch. 6), with damping ratio ξ
    // while ω dt < 2 (√(1 + ξ²) − ξ) (ibid.). The bonds' dashpots damp a particle's motion at
    // most at 4 c / m (two bonds along each axis, each pulling both ways); as if all of that
    // damped the highest mode, ξ = 2 c / (m ω). A tenth inside the undamped limit, or the damped
    // limit where that is shorter (a bulk viscosity above about 0.17).
    const double dampingRatio = 2.0 * bondDashpotNSPerM / (particleMassKg * omegaRadS);
    return std::min(0.9, std::sqrt(1.0 + dampingRatio * dampingRatio) - dampingRatio) * 2.0 / omegaRadS;
}

}  // namespace spall
