// A stationary Gaussian random field of zero mean, unit variance and squared-exponential
// correlation exp(-r^2 / (2 l^2)), by random Fourier features (Rahimi & Recht, NIPS 2007; Shinozuka
// & Deodatis, Appl. Mech. Rev. 44 (1991) 191, spectral representation): g(x) = sqrt(2/M) sum
// cos(k_m . x + phi_m), wave vectors k_m drawn from the field's spectral density N(0, I / l^2),
// phases uniform. Deterministic from its seed; its values at any points, in any order.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace spall {

class GaussianRandomField {
public:
    GaussianRandomField(uint64_t seed, double correlationLengthM, int modes = 256);
    double at(const Eigen::Vector3d& xM) const;

    const std::vector<Eigen::Vector3d>& waveVectorsPerM() const { return mWaveVectorPerM; }
    const std::vector<double>& phases() const { return mPhase; }

private:
    std::vector<Eigen::Vector3d> mWaveVectorPerM;
    std::vector<double> mPhase;
};

/// The same field at the points of a grid, x = stepM · n for integer n in [lowest, highest], a
/// few times faster than GaussianRandomField::at where a lattice asks for hundreds of thousands of
/// points: cos(k·x + φ) = Re(e^{i(φ + k_x x)} e^{i k_y y} e^{i k_z z}), each factor from a table
/// per axis, so a mode costs three complex products instead of a cosine (equal to `at` within
/// round-off, about 1e-13 of the field's unit deviation).
class GaussianRandomFieldOnGrid {
public:
    GaussianRandomFieldOnGrid(const GaussianRandomField& field, double stepM, const Eigen::Vector3i& lowest, const Eigen::Vector3i& highest);
    double at(const Eigen::Vector3i& n) const;

private:
    size_t mModes = 0;
    Eigen::Vector3i mLowest;
    /// Per axis, per grid index then mode: the factor's real and imaginary parts (x's with the phase).
    std::array<std::vector<double>, 3> mReal, mImaginary;
};

/// Variance reduction of a field of correlation length l averaged over a segment of length T:
/// gamma(T) = (2/T^2) int_0^T (T - tau) rho(tau) dtau (Vanmarcke, Random Fields, 1983, ch. 5),
/// for rho = exp(-tau^2 / (2 l^2)). 1 at T = 0; sqrt(2 pi) l / T for T >> l.
double varianceFunction(double lengthM, double correlationLengthM);

}  // namespace spall
