// A stationary Gaussian random field of zero mean, unit variance and squared-exponential
// correlation exp(-r^2 / (2 l^2)), by random Fourier features (Rahimi & Recht, NIPS 2007; Shinozuka
// & Deodatis, Appl. Mech. Rev. 44 (1991) 191, spectral representation): g(x) = sqrt(2/M) sum
// cos(k_m . x + phi_m), wave vectors k_m drawn from the field's spectral density N(0, I / l^2),
// phases uniform. Deterministic from its seed; its values at any points, in any order.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace spall {

class GaussianRandomField {
public:
    GaussianRandomField(uint64_t seed, double correlationLengthM, int modes = 256);
    double at(const Eigen::Vector3d& xM) const;

private:
    std::vector<Eigen::Vector3d> mWaveVectorPerM;
    std::vector<double> mPhase;
};

/// Variance reduction of a field of correlation length l averaged over a segment of length T:
/// gamma(T) = (2/T^2) int_0^T (T - tau) rho(tau) dtau (Vanmarcke, Random Fields, 1983, ch. 5),
/// for rho = exp(-tau^2 / (2 l^2)). 1 at T = 0; sqrt(2 pi) l / T for T >> l.
double varianceFunction(double lengthM, double correlationLengthM);

}  // namespace spall
