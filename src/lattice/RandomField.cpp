#include <spall/lattice/RandomField.h>

#include <spall/core/Hash.h>

#include <cmath>

namespace spall {

namespace {

/// Uniform in (0, 1) from a counter: splitmix64's output, 53 bits.
double uniformOpen(uint64_t seed, uint64_t counter)
{
    return (double(splitmix64(seed ^ splitmix64(counter)) >> 11) + 0.5) / 9007199254740992.0;
}

/// Standard normal (Box-Muller).
double standardNormal(uint64_t seed, uint64_t counter)
{
    return std::sqrt(-2.0 * std::log(uniformOpen(seed, 2 * counter))) * std::cos(2.0 * M_PI * uniformOpen(seed, 2 * counter + 1));
}

}  // namespace

GaussianRandomField::GaussianRandomField(uint64_t seed, double correlationLengthM, int modes)
{
    for (int m = 0; m < modes; ++m) {
        const uint64_t base = 4 * uint64_t(m);
        mWaveVectorPerM.push_back(Eigen::Vector3d(standardNormal(seed, base), standardNormal(seed, base + 1), standardNormal(seed, base + 2)) /
                                  correlationLengthM);
        mPhase.push_back(2.0 * M_PI * uniformOpen(seed, 8 * uint64_t(modes) + m));
    }
}

double GaussianRandomField::at(const Eigen::Vector3d& xM) const
{
    double sum = 0.0;
    for (size_t m = 0; m < mPhase.size(); ++m) sum += std::cos(mWaveVectorPerM[m].dot(xM) + mPhase[m]);
    return std::sqrt(2.0 / double(mPhase.size())) * sum;
}

double varianceFunction(double lengthM, double correlationLengthM)
{
    const double t = lengthM, l = correlationLengthM;
    if (t <= 1e-9 * l) return 1.0;
    return 2.0 / (t * t) * (t * l * std::sqrt(M_PI / 2.0) * std::erf(t / (std::sqrt(2.0) * l)) - l * l * (1.0 - std::exp(-t * t / (2.0 * l * l))));
}

}  // namespace spall
