// The lattice's highest frequency, which sets its stable step (issue 49). An unbounded lattice's
// linearised equations of motion have plane-wave (Bloch) solutions u_p = U e^{i k·x_p},
// θ_p = Θ e^{i k·x_p}; at each wave vector the 6 × 6 dynamical matrix D(k) gives ω² as the
// eigenvalues of M⁻¹ D (Brillouin, Wave Propagation in Periodic Structures, 1946; Ashcroft &
// Mermin, Solid State Physics, ch. 22). The largest over the zone is the bulk's highest
// frequency. A bounded lattice's is lower (its surface particles miss bonds and their λ is
// condensed, LatticeBuild.cpp), as the stepping tests measure (test_lattice_stability.cpp).
#include <spall/lattice/LatticeModel.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <vector>

namespace spall {

namespace {

using Complex = std::complex<double>;
using Matrix6c = Eigen::Matrix<Complex, 6, 6>;

/// The skew matrix of e_a × (·).
Eigen::Matrix3d crossWithAxis(int a)
{
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    m(c, b) = 1.0;
    m(b, c) = -1.0;
    return m;
}

/// D(k) for wavenumbers κ = k h in [0, π]³, per particle, from the energy of its three bonds
/// toward +x, +y, +z and its volumetric term (unit: N/m on U, N m/rad on Θ).
Matrix6c dynamicalMatrix(const LatticeStiffness& k, double h, const Eigen::Vector3d& kappa)
{
    Matrix6c d = Matrix6c::Zero();
    for (int a = 0; a < 3; ++a) {
        const Complex phase = std::polar(1.0, kappa[a]);
        // In the bond's half-way frame, linearised: its faces part by d = (φ − 1) U +
        // (h/2)(1 + φ) e_a × Θ and it turns by Δθ = (φ − 1) Θ (Lattice::strainOf).
        Matrix6c strain = Matrix6c::Zero();
        strain.topLeftCorner<3, 3>().diagonal().setConstant(phase - 1.0);
        strain.topRightCorner<3, 3>() = (0.5 * h) * (1.0 + phase) * crossWithAxis(a).cast<Complex>();
        strain.bottomRightCorner<3, 3>().diagonal().setConstant(phase - 1.0);
        Eigen::Matrix<double, 6, 1> springs;
        springs << k.shearNPerM[size_t(a)], Eigen::Vector3d::Constant(k.bendingNmPerRad[size_t(a)]);
        springs[a] = k.normalNPerM[size_t(a)];
        springs[3 + a] = k.twistingNmPerRad[size_t(a)];
        d += strain.adjoint() * springs.cast<Complex>().asDiagonal() * strain;
    }
    // ½ λ h³ (tr ε)², tr ε = i Σ_a sin(κ_a) U_a / h: the two bonds along each axis, halved.
    Eigen::Matrix<double, 6, 1> trace = Eigen::Matrix<double, 6, 1>::Zero();
    for (int a = 0; a < 3; ++a) trace[a] = std::sin(kappa[a]);
    d += (k.lameLambdaPa * h * trace * trace.transpose()).cast<Complex>();
    return d;
}

/// The largest ω² at κ (unit: rad²/s²).
double highestOmegaSquaredAt(const LatticeStiffness& k, double h, double massKg, double inertiaKgM2, const Eigen::Vector3d& kappa)
{
    Eigen::Matrix<double, 6, 1> inverseRootMass;
    inverseRootMass << Eigen::Vector3d::Constant(1.0 / std::sqrt(massKg)), Eigen::Vector3d::Constant(1.0 / std::sqrt(inertiaKgM2));
    const Matrix6c scaled = inverseRootMass.cast<Complex>().asDiagonal() * dynamicalMatrix(k, h, kappa) * inverseRootMass.cast<Complex>().asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Matrix6c>(scaled, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
}

/// The search below; for the presets its maximum lies at a corner of the zone (κ = (0, 0, π)
/// isotropic, (π, π, π) for wood), which the grid holds.
double searchHighestFrequencyRadS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg)
{
    const double inertiaKgM2 = particleMassKg * spacingM * spacingM / 6.0;  // a cube's
    const auto at = [&](const Eigen::Vector3d& kappa) { return highestOmegaSquaredAt(stiffness, spacingM, particleMassKg, inertiaKgM2, kappa); };
    // D(−κ) is D(κ)'s conjugate and each axis's reflection leaves the spectrum as it is, so
    // [0, π]³ holds every frequency: a grid over it, then a pattern search from its best point.
    constexpr int kIntervals = 12;
    const double cell = M_PI / kIntervals;
    Eigen::Vector3d best = Eigen::Vector3d::Zero();
    double bestOmega2 = at(best);
    for (int i = 0; i <= kIntervals; ++i)
        for (int j = 0; j <= kIntervals; ++j)
            for (int l = 0; l <= kIntervals; ++l) {
                const Eigen::Vector3d kappa(i * cell, j * cell, l * cell);
                if (const double omega2 = at(kappa); omega2 > bestOmega2) bestOmega2 = omega2, best = kappa;
            }
    for (double stride = 0.5 * cell; stride > 1e-6; stride *= 0.5) {
        bool improved = true;
        while (improved) {
            improved = false;
            for (int axis = 0; axis < 3; ++axis)
                for (const double sign : {-1.0, 1.0}) {
                    Eigen::Vector3d kappa = best;
                    kappa[axis] = std::clamp(kappa[axis] + sign * stride, 0.0, M_PI);
                    if (const double omega2 = at(kappa); omega2 > bestOmega2) bestOmega2 = omega2, best = kappa, improved = true;
                }
        }
    }
    return std::sqrt(bestOmega2);
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

double stableTimeStepS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg)
{
    // Central differences (velocity Verlet) are stable while ω dt < 2 (Belytschko, Liu & Moran,
    // Nonlinear Finite Elements for Continua and Structures, 2000, ch. 6); a tenth below, for
    // the dashpots and contacts beside the bonds.
    return 0.9 * 2.0 / highestFrequencyRadS(stiffness, spacingM, particleMassKg);
}

}  // namespace spall
