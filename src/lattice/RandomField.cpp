#include <spall/lattice/RandomField.h>

#include <spall/core/Hash.h>

#include <algorithm>
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

GaussianRandomFieldOnGrid::GaussianRandomFieldOnGrid(const GaussianRandomField& field, double stepM, const Eigen::Vector3i& lowest,
                                                     const Eigen::Vector3i& highest)
    : mModes(field.phases().size()), mLowest(lowest)
{
    for (int axis = 0; axis < 3; ++axis) {
        const size_t count = size_t(std::max(0, highest[axis] - lowest[axis] + 1));
        mReal[axis].resize(count * mModes);
        mImaginary[axis].resize(count * mModes);
        for (size_t i = 0; i < count; ++i)
            for (size_t m = 0; m < mModes; ++m) {
                const double angle =
                    field.waveVectorsPerM()[m][axis] * stepM * double(lowest[axis] + int(i)) + (axis == 0 ? field.phases()[m] : 0.0);
                mReal[axis][i * mModes + m] = std::cos(angle);
                mImaginary[axis][i * mModes + m] = std::sin(angle);
            }
    }
}

double GaussianRandomFieldOnGrid::at(const Eigen::Vector3i& n) const
{
    const Eigen::Vector3i i = n - mLowest;
    const double *xr = &mReal[0][size_t(i.x()) * mModes], *xi = &mImaginary[0][size_t(i.x()) * mModes];
    const double *yr = &mReal[1][size_t(i.y()) * mModes], *yi = &mImaginary[1][size_t(i.y()) * mModes];
    const double *zr = &mReal[2][size_t(i.z()) * mModes], *zi = &mImaginary[2][size_t(i.z()) * mModes];
    // Four sums side by side (mode m into sum m mod 4), which the compiler can keep in vector
    // registers; added in a fixed order, so the result does not depend on the machine.
    std::array<double, 4> sums{};
    const auto addMode = [&](size_t m, double& sum) {
        const double re = xr[m] * yr[m] - xi[m] * yi[m], im = xr[m] * yi[m] + xi[m] * yr[m];
        sum += re * zr[m] - im * zi[m];
    };
    size_t m = 0;
    for (; m + 4 <= mModes; m += 4)
        for (size_t lane = 0; lane < 4; ++lane) addMode(m + lane, sums[lane]);
    for (; m < mModes; ++m) addMode(m, sums[m % 4]);
    return std::sqrt(2.0 / double(mModes)) * ((sums[0] + sums[1]) + (sums[2] + sums[3]));
}

double varianceFunction(double lengthM, double correlationLengthM)
{
    const double t = lengthM, l = correlationLengthM;
    if (t <= 1e-9 * l) return 1.0;
    return 2.0 / (t * t) * (t * l * std::sqrt(M_PI / 2.0) * std::erf(t / (std::sqrt(2.0) * l)) - l * l * (1.0 - std::exp(-t * t / (2.0 * l * l))));
}

}  // namespace spall
