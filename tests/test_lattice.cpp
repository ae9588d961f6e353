// The deformable phase's elastic lattice against closed forms: the bar wave speed √(E/ρ), the
// first bending frequency of a cantilever (Euler–Bernoulli), and conservation of momentum and
// energy.
#include "TestUtil.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>
#include <spall/lattice/RandomField.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <functional>
#include <random>

using namespace spall;

namespace {

/// A concrete of the fib Model Code 2010's order of magnitude (C30 has E ≈ 33.6 GPa), with the
/// strength and fracture energy the tests below were written for.
Material latticeConcrete()
{
    Material m;
    m.densityKgM3 = 2400.0;
    m.youngsModulusPa = 30e9;
    m.poissonRatio = 0.2;
    m.tensileStrengthPa = 3e6;
    m.fractureEnergyJPerM2 = 100.0;
    return m;
}
const Material kConcrete = latticeConcrete();
constexpr double kH = 0.01;

Lattice latticeOfBox(int nx, int ny, int nz, const Material& material = kConcrete, const LatticeSettings& settings = LatticeSettings())
{
    Body body = test::boxBody(nx, ny, nz, kH, material.densityKgM3);
    return Lattice::fromBody(body, material, StaticWorld(), settings);
}

/// `material` with the damping ratio `zeta`.
Material damped(Material material, double zeta)
{
    material.dampingRatio = zeta;
    return material;
}

/// The deformable phase's settings with its bulk viscosity off (its dashpots would take energy,
/// or count as strength).
LatticeSettings withoutBulkViscosity()
{
    LatticeSettings settings;
    settings.bulkViscosity = 0.0;
    return settings;
}

double barWaveSpeed(const Material& m) { return std::sqrt(m.youngsModulusPa / m.densityKgM3); }

/// Steps the lattice `steps` times by dt, calling afterStep(i) after step i, and returns the
/// times at which particle p's displacement in y from where it starts turns from negative to
/// positive (interpolated within the step).
std::vector<double> upCrossingTimesS(Lattice& lattice, size_t p, double dt, int steps, const std::function<void(int)>& afterStep = {})
{
    const double restY = lattice.state.positionM[p].y();
    std::vector<double> upCrossings;
    double previous = 0.0;
    for (int i = 0; i < steps; ++i) {
        lattice.step(dt);
        const double y = lattice.state.positionM[p].y() - restY;
        if (previous < 0.0 && y >= 0.0) upCrossings.push_back((i + previous / (previous - y)) * dt);
        previous = y;
        if (afterStep) afterStep(i);
    }
    return upCrossings;
}

}  // namespace

TEST(Lattice, CalibrationGivesTheContinuumModuli)
{
    // Energy per voxel under a uniform strain equals the continuum's: C11 = kn/h + λ, C44 = ks/(2h).
    const LatticeStiffness k = calibrateLattice(kConcrete, kH);
    const double e = kConcrete.youngsModulusPa, nu = kConcrete.poissonRatio;
    const double lambda = e * nu / ((1 + nu) * (1 - 2 * nu)), mu = e / (2 * (1 + nu));
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_NEAR(k.normalNPerM[axis] / kH + k.lameLambdaPa, lambda + 2 * mu, 1e-6 * e);
        EXPECT_NEAR(k.shearNPerM[axis] / (2 * kH), mu, 1e-6 * e);
    }
}

TEST(Lattice, WoodsLatticeHasItsElasticityAlongAndAcrossTheGrain)
{
    // The bulk stiffness of a lattice with a grain along z: normal part diag(kn/h) + λ 1 1ᵀ,
    // shear C44 of a plane (a, b) = (ks_a + ks_b) / 4h. Its inverse (computed here by Eigen,
    // not by the calibration's closed form) must give the preset's E along and across the
    // grain, ν across it, and G in the planes that hold the grain.
    const Material& wood = findMaterialPreset("wood");
    ASSERT_EQ(wood.grainAxis, GrainAxis::Z);
    const LatticeStiffness k = calibrateLattice(wood, kH);
    Eigen::Matrix3d normal = Eigen::Matrix3d::Constant(k.lameLambdaPa);
    for (int axis = 0; axis < 3; ++axis) normal(axis, axis) += k.normalNPerM[axis] / kH;
    const Eigen::Matrix3d compliance = normal.inverse();
    EXPECT_NEAR(1.0 / compliance(2, 2), wood.alongGrainYoungsModulusPa, 1e-9 * wood.alongGrainYoungsModulusPa);
    EXPECT_NEAR(1.0 / compliance(0, 0), wood.youngsModulusPa, 1e-9 * wood.youngsModulusPa);
    EXPECT_NEAR(-compliance(0, 1) / compliance(0, 0), wood.poissonRatio, 1e-9);
    EXPECT_NEAR((k.shearNPerM[0] + k.shearNPerM[2]) / (4 * kH), wood.alongGrainShearModulusPa, 1e-9 * wood.alongGrainShearModulusPa);
    EXPECT_NEAR(k.shearNPerM[0] / (2 * kH), wood.youngsModulusPa / (2 * (1 + wood.poissonRatio)), 1e-9 * wood.youngsModulusPa);
    // Reciprocity of a symmetric compliance: ν_TL / ν_LT = E_T / E_L (Wood Handbook ch. 5).
    const double nuAlongToAcross = -compliance(2, 0) / compliance(2, 2), nuAcrossToAlong = -compliance(0, 2) / compliance(0, 0);
    std::printf("wood: nu_LT %.3f, nu_TL %.4f\n", nuAlongToAcross, nuAcrossToAlong);
    EXPECT_NEAR(nuAcrossToAlong / nuAlongToAcross, wood.youngsModulusPa / wood.alongGrainYoungsModulusPa, 1e-9);
    EXPECT_EQ(k.strength[1].youngsModulusPa, wood.alongGrainYoungsModulusPa);
}

TEST(Lattice, RigidPlacementStrainsNothing)
{
    Body body = test::boxBody(5, 4, 3, kH, kConcrete.densityKgM3, Eigen::Vector3d(1, -2, 0.5),
                              Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -0.4, 0.8).normalized())));
    const Lattice lattice = Lattice::fromBody(body, kConcrete);
    EXPECT_EQ(lattice.particleCount(), 60u);
    EXPECT_EQ(lattice.bondCount(), size_t(4 * 4 * 3 + 5 * 3 * 3 + 5 * 4 * 2));
    EXPECT_LT(lattice.strainEnergyJ(), 1e-20);
}

TEST(Lattice, MomentumIsConservedExactly)
{
    // Random velocities and spins in a free block: bond forces and moments come in equal and
    // opposite pairs about a common point, so linear and angular momentum stay put.
    Lattice lattice = latticeOfBox(6, 5, 4);
    std::mt19937 random(7);
    std::normal_distribution<double> normal(0.0, 1.0);
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        lattice.state.velocityMS[p] = Eigen::Vector3d(normal(random), normal(random), normal(random));
        lattice.state.angularVelocityRadS[p] = 100.0 * Eigen::Vector3d(normal(random), normal(random), normal(random));
    }
    const Eigen::Vector3d p0 = lattice.linearMomentum(), l0 = lattice.angularMomentumAboutOrigin();
    const double dt = lattice.stableTimeStepS();
    for (int i = 0; i < 2000; ++i) lattice.step(dt);
    const double scale = lattice.model().particleMassKg * std::sqrt(double(lattice.particleCount()));
    EXPECT_LT((lattice.linearMomentum() - p0).norm(), 1e-12 * scale);
    EXPECT_LT((lattice.angularMomentumAboutOrigin() - l0).norm(), 1e-12 * scale * 0.1);
}

TEST(Lattice, DampingKeepsMomentaAndRigidMotionAndTakesOnlyVibration)
{
    // Mass-proportional damping about each piece's rigid motion: in a free block broken in two
    // and shaken at random, each piece keeps its linear and angular momentum while its
    // vibration dies; a block spinning rigidly keeps its kinetic energy.
    Lattice lattice = latticeOfBox(8, 4, 3, damped(kConcrete, 0.05));
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (lattice.model().bonds[b].axis == 0 && lattice.model().voxel[lattice.model().bonds[b].low].x() == 3) lattice.state.bondHistory[b].damageDriverM = 1.0;
    std::mt19937 random(11);
    std::normal_distribution<double> normal(0.0, 1.0);
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        lattice.state.velocityMS[p] = Eigen::Vector3d(normal(random), normal(random), normal(random));
        lattice.state.angularVelocityRadS[p] = 100.0 * Eigen::Vector3d(normal(random), normal(random), normal(random));
    }
    lattice.refreshForces();
    const Eigen::Vector3d p0 = lattice.linearMomentum(), l0 = lattice.angularMomentumAboutOrigin();
    const double energyStart = lattice.kineticEnergyJ() + lattice.strainEnergyJ();
    const double dt = lattice.stableTimeStepS();
    for (int i = 0; i < 2000; ++i) lattice.step(dt);
    const double scale = lattice.model().particleMassKg * std::sqrt(double(lattice.particleCount()));
    EXPECT_LT((lattice.linearMomentum() - p0).norm(), 1e-12 * scale);
    EXPECT_LT((lattice.angularMomentumAboutOrigin() - l0).norm(), 1e-12 * scale * 0.1);
    const double energyEnd = lattice.kineticEnergyJ() + lattice.strainEnergyJ();
    std::printf("damped block: energy %.3e J -> %.3e J over %.2f ms\n", energyStart, energyEnd, 2000 * dt * 1e3);
    EXPECT_LT(energyEnd, 0.5 * energyStart);

    Lattice spinning = latticeOfBox(8, 4, 3, damped(kConcrete, 0.05), withoutBulkViscosity());
    const Eigen::Vector3d spin(0.0, 0.0, 20.0);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& x : spinning.state.positionM) centre += x / double(spinning.particleCount());
    for (size_t p = 0; p < spinning.particleCount(); ++p) {
        spinning.state.velocityMS[p] = spin.cross(spinning.state.positionM[p] - centre);
        spinning.state.angularVelocityRadS[p] = spin;
    }
    const double rigidEnergy = spinning.kineticEnergyJ();
    for (int i = 0; i < 2000; ++i) spinning.step(dt);
    const double kept = (spinning.kineticEnergyJ() + spinning.strainEnergyJ()) / rigidEnergy;
    std::printf("spinning block: energy kept %.9f\n", kept);
    EXPECT_NEAR(kept, 1.0, 1e-6);
}

TEST(Lattice, DampedCantileverDecaysAtTheMaterialsDampingRatio)
{
    // A cantilever of square section, 4 voxels thick and 40 long beyond its held layer, set
    // moving in its first mode with ζ = 0.05: successive peaks of its tip fall by the
    // logarithmic decrement δ = 2πζ / √(1 − ζ²) (Clough & Penzien §2-7) of the ratio the piece's
    // damping takes at its estimated fundamental frequency.
    const int free = 40, thick = 4;
    const double zeta = 0.05;
    Body body = test::boxBody(free + 1, thick, thick, kH, kConcrete.densityKgM3);
    auto acc = body.grid->getAccessor();
    for (int y = 0; y < thick; ++y)
        for (int z = 0; z < thick; ++z) acc.setValue(openvdb::Coord(0, y, z), acc.getValue(openvdb::Coord(0, y, z)) | kAnchorBit);
    Lattice lattice = Lattice::fromBody(body, damped(kConcrete, zeta), StaticWorld(), withoutBulkViscosity());
    const double lengthM = (free + 0.5) * kH;
    const double beta = 1.8751 / lengthM, sigma = 0.7341;
    const double x0 = lattice.state.positionM[0].x();
    size_t tip = 0;
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        if (lattice.model().voxel[p] == openvdb::Coord(free, thick / 2, thick / 2)) tip = p;
        if (lattice.model().held[p]) continue;
        const double x = beta * (lattice.state.positionM[p].x() - x0);
        lattice.state.velocityMS[p] = Eigen::Vector3d(0, 0.005 * (std::cosh(x) - std::cos(x) - sigma * (std::sinh(x) - std::sin(x))), 0);
    }
    const double dt = lattice.stableTimeStepS();
    const double restY = lattice.state.positionM[tip].y();
    // The largest displacement in each cycle, a cycle ending at an up-crossing.
    std::vector<double> peaks{0.0};
    // A held piece's length is its farthest reach from the held layer, plus half a voxel.
    const double estimatedRadS = lattice.fundamentalFrequencyRadS(thick * kH, lengthM, true);
    const int steps = int(5.2 * 2 * M_PI / estimatedRadS / dt);
    std::vector<double> upCrossings = upCrossingTimesS(lattice, tip, dt, steps, [&](int) {
        const double y = lattice.state.positionM[tip].y() - restY;
        if (y < 0.0 && peaks.back() > 0.0) peaks.push_back(0.0);
        peaks.back() = std::max(peaks.back(), y);
    });
    ASSERT_GE(peaks.size(), 4u);
    ASSERT_GE(upCrossings.size(), 3u);
    const double decrement = std::log(peaks[0] / peaks[3]) / 3.0;
    const double measured = decrement / std::sqrt(4 * M_PI * M_PI + decrement * decrement);
    const double frequencyRadS = 2 * M_PI * double(upCrossings.size() - 1) / (upCrossings.back() - upCrossings.front());
    std::printf("damped cantilever: zeta %.4f measured against %.4f set; first mode %.1f rad/s, estimated %.1f rad/s (%+.1f %%)\n",
                measured, zeta, frequencyRadS, estimatedRadS, 100 * (estimatedRadS / frequencyRadS - 1));
    // The decay is exact for the estimate's frequency: ζ_measured = ζ ω_estimated / ω.
    EXPECT_NEAR(measured, zeta * estimatedRadS / frequencyRadS, 0.03 * zeta);
    // And the estimate is a beam's: within 10 % of the lattice's own first mode.
    EXPECT_NEAR(estimatedRadS, frequencyRadS, 0.10 * frequencyRadS);
}

TEST(Lattice, AWallHeldAlongItsBaseIsDampedAtItsHeightsCantileverMode)
{
    // A wall 30 voxels long, 20 high and 4 thick, held along its base, set swinging in its
    // first mode with ζ = 0.05: its tip's peaks must fall at ζ within 10 %. Its damping takes
    // the piece's farthest reach from its base as the cantilever, not its longest side (which
    // gave (20.5/30)² = 0.47 of ζ here). The mode is a plate's clamped along one edge, free on
    // three (Leissa 1969, ch. 4.3: within a few % of the beam's at this aspect).
    const int length = 30, high = 20, thick = 4;
    const double zeta = 0.05;
    Body body = test::boxBody(length, thick, high + 1, kH, kConcrete.densityKgM3);
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (it.getCoord().z() == 0) it.setValue(*it | kAnchorBit);
    Lattice lattice = Lattice::fromBody(body, damped(kConcrete, zeta), StaticWorld(), withoutBulkViscosity());
    const double heightM = (high + 0.5) * kH, beta = 1.8751 / heightM, sigma = 0.7341;
    const double z0 = lattice.state.positionM[0].z();
    size_t tip = 0;
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        if (lattice.model().voxel[p] == openvdb::Coord(length / 2, thick / 2, high)) tip = p;
        if (lattice.model().held[p]) continue;
        const double x = beta * (lattice.state.positionM[p].z() - z0);
        lattice.state.velocityMS[p] = Eigen::Vector3d(0, 0.005 * (std::cosh(x) - std::cos(x) - sigma * (std::sinh(x) - std::sin(x))), 0);
    }
    const double dt = lattice.stableTimeStepS(), restY = lattice.state.positionM[tip].y();
    std::vector<double> peaks{0.0};
    const int steps = int(3.2 * 2 * M_PI / lattice.fundamentalFrequencyRadS(thick * kH, heightM, true) / dt);
    upCrossingTimesS(lattice, tip, dt, steps, [&](int) {
        const double y = lattice.state.positionM[tip].y() - restY;
        if (y < 0.0 && peaks.back() > 0.0) peaks.push_back(0.0);
        peaks.back() = std::max(peaks.back(), y);
    });
    ASSERT_GE(peaks.size(), 3u);
    const double decrement = std::log(peaks[0] / peaks[2]) / 2.0;
    const double measured = decrement / std::sqrt(4 * M_PI * M_PI + decrement * decrement);
    std::printf("wall held along its base: zeta %.4f measured against %.4f set\n", measured, zeta);
    EXPECT_NEAR(measured, zeta, 0.1 * zeta);
}

TEST(Lattice, ParticlesThatShareNoBondCollideAsSmoothSpheres)
{
    // Two particles of one lattice that were never neighbours (four voxels apart, no bond), thrown
    // at each other at 5 m/s, 0.3 of an edge off centre. Reference: the elastic collision of two
    // equal smooth spheres (the particles meet as spheres of the edge's diameter): the relative
    // velocity's component along the line of centres at contact reverses, the rest is kept.
    // Before pieces of one lattice met, they passed through each other.
    Body body = makeBody(test::gridFromVoxels({openvdb::Coord(0, 0, 0), openvdb::Coord(4, 0, 0)}, kH), kH, kConcrete.densityKgM3);
    Lattice lattice = Lattice::fromBody(body, kConcrete);
    ASSERT_EQ(lattice.bondCount(), 0u);
    const double offset = 0.3;
    lattice.state.positionM[1].y() += offset * kH;
    lattice.state.velocityMS[0] = Eigen::Vector3d(5, 0, 0);
    lattice.state.velocityMS[1] = Eigen::Vector3d(-5, 0, 0);
    lattice.refreshForces();
    const Eigen::Vector3d p0 = lattice.linearMomentum();
    const double e0 = lattice.kineticEnergyJ();
    double closest = 1e30;
    const double dt = lattice.stableTimeStepS();
    for (double t = 0; t < 8 * kH / 10.0; t += dt) {
        lattice.step(dt);
        closest = std::min(closest, (lattice.state.positionM[1] - lattice.state.positionM[0]).norm());
    }
    const Eigen::Vector3d n(std::sqrt(1 - offset * offset), offset, 0);  // from 0 to 1 at contact
    const Eigen::Vector3d relative(10, 0, 0), exchange = relative.dot(n) * n;
    // Within 0.5 % of the relative speed (measured 0.22 %): the spring is soft enough that the
    // spheres slide 27 µm past each other while they touch, turning the line of centres.
    EXPECT_LT((lattice.state.velocityMS[0] - (Eigen::Vector3d(5, 0, 0) - exchange)).norm(), 5e-3 * 10);
    EXPECT_LT((lattice.state.velocityMS[1] - (Eigen::Vector3d(-5, 0, 0) + exchange)).norm(), 5e-3 * 10);
    EXPECT_LT((lattice.linearMomentum() - p0).norm(), 1e-12 * lattice.model().particleMassKg * 5);
    // The contact lasts about four steps: velocity Verlet with a force that starts within a step
    // loses a little (0.47 %), and must not gain.
    EXPECT_LT(lattice.kineticEnergyJ(), e0);
    EXPECT_GT(lattice.kineticEnergyJ(), 0.99 * e0);
    EXPECT_GT(closest, 0.95 * kH);
}

TEST(Lattice, OneAndTwoThreadsGiveTheSameBits)
{
    // Large enough to step in parallel; bonds add forces in fixed batches, so every particle's
    // sum has one order whatever the thread count (and damping sums its pieces in fixed chunks).
    auto run = [](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        Lattice lattice = latticeOfBox(24, 24, 16, damped(kConcrete, 0.05));
        std::mt19937 random(11);
        std::normal_distribution<double> normal(0.0, 0.05);
        for (Eigen::Vector3d& v : lattice.state.velocityMS) v = Eigen::Vector3d(normal(random), normal(random), normal(random));
        for (int i = 0; i < 20; ++i) lattice.step(lattice.stableTimeStepS());
        return lattice.state.positionM;
    };
    const std::vector<Eigen::Vector3d> one = run(1), two = run(2);
    ASSERT_EQ(one.size(), two.size());
    for (size_t p = 0; p < one.size(); ++p) ASSERT_EQ(one[p], two[p]) << p;
}

TEST(Lattice, ABeamHeldByTwoBoxesBendsAtTheClampedClampedFrequency)
{
    // A beam 120 voxels long, 8 thick and 2 wide, its end layers anchored against two boxes (a
    // collider at each end): each end voxel is bonded to a held point in the box, a voxel beyond
    // its end face, so the beam is clamped at those points' centres, a span of 121 voxels.
    // Euler–Bernoulli, clamped–clamped: f1 = 4.7300² / (2π L²) √(EI/(ρA)) (Clough & Penzien,
    // table 18-1). Timoshenko's shear correction at this slenderness is about −1.6 %.
    const int length = 120, thick = 8;
    Body body = test::boxBody(length, thick, 2, kH, kConcrete.densityKgM3);
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (it.getCoord().x() == 0 || it.getCoord().x() == length - 1) it.setValue(*it | kAnchorBit);
    const double halfLengthM = 0.5 * length * kH;
    StaticWorld supports;
    for (const double side : {-1.0, 1.0})
        supports.boxes.push_back({Eigen::Vector3d(side * (halfLengthM + 0.5), 0, 0), Eigen::Vector3d(0.5, 1, 1), Eigen::Quaterniond::Identity()});
    Lattice lattice = Lattice::fromBody(body, kConcrete, supports, withoutBulkViscosity());
    ASSERT_EQ(lattice.particleCount() - lattice.model().voxelParticleCount, size_t(2 * thick * 2)) << "one held point per anchored voxel";
    for (size_t p = lattice.model().voxelParticleCount; p < lattice.particleCount(); ++p) {
        const int x = lattice.model().voxel[p].x();
        ASSERT_TRUE(x == -1 || x == length) << "a held point beyond an end face, not a side";
    }
    const double spanM = (length + 1) * kH, t = thick * kH;
    const double expected = 4.7300 * 4.7300 / (2 * M_PI * spanM * spanM) * std::sqrt(kConcrete.youngsModulusPa * t * t / 12 / kConcrete.densityKgM3);
    // The first mode's shape as velocities in y, x from the left held point.
    const double beta = 4.7300 / spanM, sigma = 0.982502;
    const double x0 = -halfLengthM - 0.5 * kH;
    size_t middle = 0;
    for (size_t p = 0; p < lattice.model().voxelParticleCount; ++p) {
        const double x = beta * (lattice.state.positionM[p].x() - x0);
        const double shape = std::cosh(x) - std::cos(x) - sigma * (std::sinh(x) - std::sin(x));
        lattice.state.velocityMS[p] = Eigen::Vector3d(0, 0.01 * shape / 1.6, 0);
        if (lattice.model().voxel[p] == openvdb::Coord(length / 2, thick / 2, 0)) middle = p;
    }
    const double dt = lattice.stableTimeStepS();
    const std::vector<double> upCrossings = upCrossingTimesS(lattice, middle, dt, int(2.2 / expected / dt));
    ASSERT_GE(upCrossings.size(), 2u);
    const double frequency = 1.0 / (upCrossings[1] - upCrossings[0]);
    std::printf("clamped-clamped beam: f1 = %.2f Hz measured, %.2f Hz Euler-Bernoulli (%+.2f %%)\n", frequency, expected,
                100 * (frequency / expected - 1));
    EXPECT_NEAR(frequency, expected, 0.05 * expected);
}

namespace {

/// A square pane of glass, `side` voxels of 5 mm across (in x and z) and `layers` thick (in y),
/// its edge voxels held by four boxes beyond its edges, set moving in the shape of a simply
/// supported plate's first mode, sin(πx/a) sin(πz/a) with a the span between the edge voxels'
/// centres. Returns its frequency, measured at its centre (unit: Hz), and the span (unit: m).
std::pair<double, double> paneFrequencyHz(int side, int layers, bool pinned)
{
    const Material glass = findMaterialPreset("glass");
    const double h = 0.005;
    Body body = test::boxBody(side, layers, side, h, glass.densityKgM3);
    for (auto it = body.grid->beginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        if (c.x() == 0 || c.x() == side - 1 || c.z() == 0 || c.z() == side - 1) it.setValue(*it | kAnchorBit);
    }
    const double halfM = 0.5 * side * h;
    StaticWorld supports;
    for (const double sign : {-1.0, 1.0}) {
        supports.boxes.push_back({Eigen::Vector3d(sign * (halfM + 0.5), 0, 0), Eigen::Vector3d(0.5, 1, 1), Eigen::Quaterniond::Identity()});
        supports.boxes.push_back({Eigen::Vector3d(0, 0, sign * (halfM + 0.5)), Eigen::Vector3d(1, 1, 0.5), Eigen::Quaterniond::Identity()});
    }
    supports.pinned.assign(supports.boxes.size(), pinned ? 1 : 0);
    Lattice lattice = Lattice::fromBody(body, glass, supports, withoutBulkViscosity());
    const double spanM = (side - 1) * h;
    size_t centre = 0;
    for (size_t p = 0; p < lattice.model().voxelParticleCount; ++p) {
        const Eigen::Vector3d fromEdgeM = lattice.state.positionM[p] + Eigen::Vector3d::Constant(halfM - 0.5 * h);
        lattice.state.velocityMS[p] = Eigen::Vector3d(0, 0.01 * std::sin(M_PI * fromEdgeM.x() / spanM) * std::sin(M_PI * fromEdgeM.z() / spanM), 0);
        if (lattice.model().voxel[p] == openvdb::Coord(side / 2, 0, side / 2)) centre = p;
    }
    const double dt = lattice.stableTimeStepS();
    // Simply supported (Leissa, Vibration of Plates, NASA SP-160, 1969, eq. 4.20): ω = 2π² / a²
    // √(D / ρt); the run lasts 2.2 of its periods, or of the clamped plate's, shorter.
    const double thicknessM = layers * h;
    const double plateD = glass.youngsModulusPa * std::pow(thicknessM, 3) / (12 * (1 - glass.poissonRatio * glass.poissonRatio));
    const double simplySupportedHz = M_PI / (spanM * spanM) * std::sqrt(plateD / (glass.densityKgM3 * thicknessM));
    const std::vector<double> upCrossings = upCrossingTimesS(lattice, centre, dt, int(2.2 / simplySupportedHz / dt));
    if (upCrossings.size() < 2) return {0.0, spanM};
    return {1.0 / (upCrossings[1] - upCrossings[0]), spanM};
}

}  // namespace

TEST(Lattice, APanePinnedAtItsEdgesVibratesAsASimplySupportedPlate)
{
    // Kirchhoff plates, square, side a, D = E t³ / 12(1 − ν²) (Leissa 1969, table 4.22 and eq.
    // 4.20): simply supported ω a² √(ρt/D) = 2π² = 19.74, clamped 35.99. A pane held by boxes
    // that hold by a pin must ring at the first; held by a bond of its own, near the second.
    // One layer of voxels has no Poisson coupling in bending and a square beam's torsion (0.84
    // of a plate strip's): its D is (1 − ν²) and its twisting stiffness 0.67 of the plate's, so
    // it rings about 10 % low; two layers bend by stretching and are closer.
    const int side = 40;
    const Material glass = findMaterialPreset("glass");
    for (const int layers : {1, 2}) {
        const auto [pinnedHz, spanM] = paneFrequencyHz(side, layers, true);
        const auto [clampedHz, unusedSpanM] = paneFrequencyHz(side, layers, false);
        const double t = layers * 0.005;
        const double plateD = glass.youngsModulusPa * t * t * t / (12 * (1 - glass.poissonRatio * glass.poissonRatio));
        const double unitHz = std::sqrt(plateD / (glass.densityKgM3 * t)) / (2 * M_PI * spanM * spanM);
        const double simplySupportedHz = 2 * M_PI * M_PI * unitHz, clampedPlateHz = 35.99 * unitHz;
        std::printf("pane %d x %d voxels, %d thick: pinned %.1f Hz against simply supported %.1f Hz (%+.1f %%); held by bonds %.1f Hz "
                    "against clamped %.1f Hz (%+.1f %%)\n",
                    side, side, layers, pinnedHz, simplySupportedHz, 100 * (pinnedHz / simplySupportedHz - 1), clampedHz, clampedPlateHz,
                    100 * (clampedHz / clampedPlateHz - 1));
        EXPECT_NEAR(pinnedHz, simplySupportedHz, (layers == 1 ? 0.12 : 0.05) * simplySupportedHz);
        EXPECT_GT(clampedHz, 1.5 * pinnedHz) << "a bond of the material's own clamps";
    }
}

TEST(Lattice, APinnedEdgePushedAlongItsPinStopsAtTheFrame)
{
    // A pin carries nothing along its axis (glazing's clearance), so only the frame itself can
    // stop a pane's edge driven into it. A row of four glass voxels along x, its first pinned to
    // a box beyond its -x face, pushed toward the box by a hundred times its weight per voxel:
    // it slides until its first cube sinks a quarter voxel into the box (Lattice::keepOutOf),
    // then stops there. Without the box's contact it slid in without limit (a shard of the glass
    // pane scene came out through its frame at 157 m/s).
    const Material glass = findMaterialPreset("glass");
    const double h = 0.005;
    Body body = test::boxBody(4, 1, 1, h, glass.densityKgM3);
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (it.getCoord().x() == 0) it.setValue(*it | kAnchorBit);
    const double boxFaceM = -2.0 * h;  // the row spans x from -2h to 2h
    StaticWorld supports;
    supports.boxes.push_back({Eigen::Vector3d(boxFaceM - 0.05, 0, 0), Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Quaterniond::Identity()});
    supports.pinned = {1};
    Lattice lattice = Lattice::fromBody(body, glass, supports);
    ASSERT_EQ(lattice.particleCount(), size_t(5)) << "one pin";
    const size_t first = size_t(lattice.particleAt(openvdb::Coord(0, 0, 0)));
    const Eigen::Vector3d push(-100.0 * lattice.model().particleMassKg * 9.81, 0, 0);
    const double dt = lattice.stableTimeStepS();
    double deepestM = -1.0;
    for (int step = 0; step < 20000; ++step) {
        for (size_t p = 0; p < lattice.model().voxelParticleCount; ++p) lattice.externalForceN[p] = push;
        lattice.step(dt);
        // How far the first voxel's cube reaches into the box.
        deepestM = std::max(deepestM, boxFaceM - (lattice.state.positionM[first].x() - 0.5 * h));
    }
    std::printf("pinned edge pushed into its frame: deepest %.3f voxel into the box, at the end moving %.2e m/s\n", deepestM / h,
                lattice.state.velocityMS[first].x());
    EXPECT_GT(deepestM, 0.2 * h) << "the pin does not stop it";
    EXPECT_LE(deepestM, 0.25 * h + 1e-12);
    // Stopped, but for one step's push of the whole row on it.
    EXPECT_LE(std::abs(lattice.state.velocityMS[first].x()), dt * 4.0 * push.norm() / lattice.model().particleMassKg);
}

TEST(Lattice, LongitudinalPulseTravelsAtTheBarSpeed)
{
    // A half-sine force pulse on one end of a 160 × 4 × 4 bar, 30 voxels long (far above the
    // thickness, so the bar speed √(E/ρ) applies: Pochhammer's correction is below 0.5 %). The
    // speed is the distance between two stations over the time between the pulse's peaks there.
    const int length = 160;
    Lattice lattice = latticeOfBox(length, 4, 4);
    const double c = barWaveSpeed(kConcrete), dt = lattice.stableTimeStepS();
    const double pulseS = 30.0 * kH / c;
    const int stationA = 40, stationB = 120;
    double peakA = 0.0, peakB = 0.0, timeA = 0.0, timeB = 0.0;
    auto meanVelocityX = [&](int x) {
        double sum = 0.0;
        int count = 0;
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.model().voxel[p].x() == x) sum += lattice.state.velocityMS[p].x(), ++count;
        return sum / count;
    };
    const int steps = int((stationB + 40) * kH / c / dt);
    for (int i = 0; i < steps; ++i) {
        const double t = i * dt;
        const double force = t < pulseS ? 1e3 * std::sin(M_PI * t / pulseS) : 0.0;
        for (size_t p = 0; p < lattice.particleCount(); ++p) lattice.externalForceN[p] = Eigen::Vector3d(lattice.model().voxel[p].x() == 0 ? force : 0.0, 0, 0);
        lattice.step(dt);
        const double va = meanVelocityX(stationA), vb = meanVelocityX(stationB);
        if (va > peakA) peakA = va, timeA = t + dt;
        if (vb > peakB) peakB = vb, timeB = t + dt;
    }
    const double speed = (stationB - stationA) * kH / (timeB - timeA);
    std::printf("bar wave: %.1f m/s measured, %.1f m/s = sqrt(E/rho) (%+.2f %%), dt = %.3g s\n", speed, c, 100 * (speed / c - 1), dt);
    EXPECT_NEAR(speed, c, 0.03 * c);
}

TEST(Lattice, CantileverBendsAtTheEulerBernoulliFrequency)
{
    // A cantilever 8 voxels thick, 2 wide and 80 long beyond its held layer, set moving in the
    // shape of its first mode. Euler–Bernoulli: f1 = 1.8751² / (2π L²) √(EI/(ρA)), I/A = t²/12,
    // L from the held layer's centre to the free end. Energy with no damping must not drift.
    const int free = 80, thick = 8;
    Body body = test::boxBody(free + 1, thick, 2, kH, kConcrete.densityKgM3);
    auto acc = body.grid->getAccessor();
    for (int y = 0; y < thick; ++y)
        for (int z = 0; z < 2; ++z) acc.setValue(openvdb::Coord(0, y, z), acc.getValue(openvdb::Coord(0, y, z)) | kAnchorBit);
    Lattice lattice = Lattice::fromBody(body, kConcrete, StaticWorld(), withoutBulkViscosity());  // energy must be conserved
    const double lengthM = (free + 0.5) * kH, t = thick * kH;
    const double expected = 1.8751 * 1.8751 / (2 * M_PI * lengthM * lengthM) * std::sqrt(kConcrete.youngsModulusPa * t * t / 12 / kConcrete.densityKgM3);
    // The first mode's shape (Euler–Bernoulli, clamped–free), as velocities in y.
    const double beta = 1.8751 / lengthM, sigma = 0.7341;
    const double x0 = lattice.state.positionM[0].x();
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        if (lattice.model().held[p]) continue;
        const double x = beta * (lattice.state.positionM[p].x() - x0);
        const double shape = std::cosh(x) - std::cos(x) - sigma * (std::sinh(x) - std::sin(x));
        lattice.state.velocityMS[p] = Eigen::Vector3d(0, 0.01 * shape / 2.0, 0);
    }
    const double dt = lattice.stableTimeStepS();
    const int steps = int(2.2 / expected / dt);
    size_t tip = 0;
    for (size_t p = 0; p < lattice.particleCount(); ++p)
        if (lattice.model().voxel[p] == openvdb::Coord(free, thick / 2, 0)) tip = p;
    double energyStart = 0.0, energyEnd = 0.0;
    const int window = 500;
    const std::vector<double> upCrossings = upCrossingTimesS(lattice, tip, dt, steps, [&](int i) {
        if (i < window) energyStart += (lattice.kineticEnergyJ() + lattice.strainEnergyJ()) / window;
        if (i >= steps - window) energyEnd += (lattice.kineticEnergyJ() + lattice.strainEnergyJ()) / window;
    });
    ASSERT_GE(upCrossings.size(), 2u);
    const double frequency = 1.0 / (upCrossings[1] - upCrossings[0]);
    std::printf("cantilever: f1 = %.2f Hz measured, %.2f Hz Euler-Bernoulli (%+.2f %%); energy drift %.2e over %d steps\n", frequency,
                expected, 100 * (frequency / expected - 1), (energyEnd - energyStart) / energyStart, steps);
    EXPECT_NEAR(frequency, expected, 0.05 * expected);
    EXPECT_LT(std::abs(energyEnd - energyStart), 1e-6 * energyStart);
}

namespace {

struct BarPull {
    double dissipatedJ = 0.0, peakStressPa = 0.0, youngsModulusPa = 0.0;
    int broken = 0, across = 0, damagedElsewhere = 0;
    int brokenAnywhere = 0;  ///< bonds along any axis, anywhere
};

/// A bar pulled apart in direct tension: `material`, length × side × side, voxel size h, one end
/// pulled at pullMS, the bonds across its middle `notch` times as strong as the rest.
struct BarSpec {
    Material material = kConcrete;
    double lengthM = 0.04, sideM = 0.02, h = 0.01, pullMS = 0.05, notch = 0.8;
    LatticeDamageLaw law = LatticeDamageLaw::Softening;
    double bulkViscosity = LatticeSettings().bulkViscosity;
};

/// The bar's end layers held (the grips), one end pulled (the whole bar starting on the matching
/// uniform strain rate, so no shock runs ahead) until it could have broken through at its notch
/// (bonds 20 % weaker across the middle by default: the stress rises 7 % while an unloading wave
/// crosses half the bar at 0.05 m/s, so a weaker notch could crack twice). Energy balance: work
/// done on the held ends minus what is left as kinetic and strain energy is what the crack took.
/// E is the stress over the mean strain between the grips when the stress first reaches ft/2.
/// What a bar of the material pulled along x should show: along the grain when it lies along x.
struct TensionTarget {
    double youngsModulusPa, tensileStrengthPa, fractureEnergyJPerM2;
    int strengthClass;
};
TensionTarget tensionTargetOf(const Material& m)
{
    if (m.grainAxis == GrainAxis::X) return {m.alongGrainYoungsModulusPa, m.alongGrainTensileStrengthPa, m.alongGrainFractureEnergyJPerM2, 1};
    return {m.youngsModulusPa, m.tensileStrengthPa, m.fractureEnergyJPerM2, 0};
}

BarPull pullBarApart(const BarSpec& spec)
{
    const Material& material = spec.material;
    const TensionTarget target = tensionTargetOf(material);
    const double h = spec.h, pullMS = spec.pullMS, sideM = spec.sideM;
    const int nx = int(std::lround(spec.lengthM / h)), ny = int(std::lround(sideM / h));
    Body body = test::boxBody(nx, ny, ny, h, material.densityKgM3);
    for (auto it = body.grid->tree().beginValueOn(); it; ++it)
        if (it.getCoord().x() == 0 || it.getCoord().x() == nx - 1) it.setValue(*it | kAnchorBit);
    LatticeSettings settings;
    settings.damageLaw = spec.law;
    settings.bulkViscosity = spec.bulkViscosity;
    Lattice lattice = Lattice::fromBody(body, material, StaticWorld(), settings);
    const double x0 = lattice.state.positionM[0].x(), gaugeM = (nx - 1) * h;
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        lattice.state.velocityMS[p] = Eigen::Vector3d(pullMS * (lattice.state.positionM[p].x() - x0) / gaugeM, 0, 0);
        if (lattice.model().held[p] && lattice.model().voxel[p].x() == 0) lattice.state.velocityMS[p].setZero();
    }
    // Held layers cannot contract sideways, which concentrates stress at the grips' corners (more
    // sharply the finer h): the quarters next to the grips are 50 % stronger, as a dog-bone
    // specimen's are thicker.
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        const int x = lattice.model().voxel[lattice.model().bonds[b].low].x();
        if (x < nx / 4 || x >= nx - nx / 4) lattice.state.bondHistory[b].strengthScale = 1.5;
        if (lattice.model().bonds[b].axis == 0 && x == nx / 2 - 1) lattice.state.bondHistory[b].strengthScale = spec.notch;
    }
    const double energy0 = lattice.kineticEnergyJ() + lattice.strainEnergyJ();
    const double dt = lattice.stableTimeStepS();
    // Long enough to stretch the bar to its strength and open the crack through.
    const double pullTimeS =
        1.5 * (lattice.model().stiffness.strength[target.strengthClass].zeroTractionStretchM + target.tensileStrengthPa / target.youngsModulusPa * gaugeM) /
        pullMS;
BarPull result;
    double workJ = 0.0;
    auto heldPower = [&] {  // the agent holding the ends balances the bonds' force on them
        double power = 0.0;
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.model().held[p]) power -= lattice.state.bondForceN[p].dot(lattice.state.velocityMS[p]);
        return power;
    };
    for (double t = 0.0; t < pullTimeS; t += dt) {
        const double before = heldPower();
        lattice.step(dt);
        workJ += 0.5 * (before + heldPower()) * dt;
        const double stressPa = heldPower() / pullMS / (sideM * sideM);
        if (result.youngsModulusPa == 0.0 && stressPa >= 0.5 * target.tensileStrengthPa)
            result.youngsModulusPa = stressPa / (pullMS * (t + dt) / gaugeM);
        result.peakStressPa = std::max(result.peakStressPa, stressPa);
    }
    result.dissipatedJ = workJ - (lattice.kineticEnergyJ() + lattice.strainEnergyJ() - energy0);
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        result.brokenAnywhere += lattice.bondDamage(b) == 1.0;
        if (lattice.model().bonds[b].axis != 0) continue;
        const bool middle = lattice.model().voxel[lattice.model().bonds[b].low].x() == nx / 2 - 1;
        result.across += middle;
        result.broken += middle && lattice.bondDamage(b) == 1.0;
        result.damagedElsewhere += !middle && lattice.bondDamage(b) > 0.5;
    }
    return result;
}

}  // namespace

TEST(Lattice, BarPulledApartDissipatesTheFractureEnergyAtEveryVoxelSize)
{
    // Crack band regularisation must make the energy the crack took Gf × the bar's section at
    // h, h/2 and h/4.
    const double expectedJ = kConcrete.fractureEnergyJPerM2 * 0.02 * 0.02;
    for (const int perCm : {1, 2, 4}) {
        const double h = 0.01 / perCm;
        BarSpec spec;
        spec.h = h;
        const BarPull pull = pullBarApart(spec);
        std::printf("h = %.4f m: dissipated %.4f J, Gf x area %.4f J (%+.1f %%); %d of %d bonds across broken, %d damaged elsewhere\n", h,
                    pull.dissipatedJ, expectedJ, 100 * (pull.dissipatedJ / expectedJ - 1), pull.broken, pull.across, pull.damagedElsewhere);
        EXPECT_EQ(pull.broken, pull.across) << "the bar did not break through at h = " << h;
        EXPECT_EQ(pull.damagedElsewhere, 0) << "a second crack at h = " << h;
        EXPECT_NEAR(pull.dissipatedJ, expectedJ, 0.10 * expectedJ) << "h = " << h;
    }
}

namespace {

/// The presets as a direct tension test sees them: quasi-static (no strain-rate law; the fib
/// DIF has its own test), without concrete's strength scatter, brick masonry as its two
/// materials, the joints and the bricks, and wood across its grain and along it.
std::vector<std::pair<std::string, Material>> presetsInTension()
{
    std::vector<std::pair<std::string, Material>> out;
    for (const char* name : {"glass", "wood", "concrete"}) {
        Material m = findMaterialPreset(name);
        m.strengthRateLaw = StrengthRateLaw::None;
        m.strengthCoefficientOfVariation = 0.0;  // the mean properties; the scatter has its own test
        out.push_back({name, m});
    }
    out[1].first = "wood across the grain";
    Material alongGrain = out[1].second;
    alongGrain.grainAxis = GrainAxis::X;
    out.push_back({"wood along the grain", alongGrain});
    Material joints = findMaterialPreset("brick-masonry");
    Material bricks = joints;
    joints.unitLengthM = 0.0;
    bricks.unitLengthM = 0.0;
    bricks.tensileStrengthPa = joints.unitTensileStrengthPa;
    bricks.fractureEnergyJPerM2 = joints.unitFractureEnergyJPerM2;
    bricks.shearStrengthPa = joints.unitShearStrengthPa;
    bricks.frictionCoefficient = joints.unitFrictionCoefficient;
    out.push_back({"brick-masonry joints", joints});
    out.push_back({"brick-masonry bricks", bricks});
    return out;
}

}  // namespace

TEST(Lattice, EveryPresetPulledApartGivesItsModulusStrengthAndFractureEnergyAtTwoVoxelSizes)
{
    // Issue 18: E within 5 %, tensile strength and Gf within 10 %, at side/4 and side/8. A bar of
    // 8 x 2 x 2 cm (four times as long as wide, so the grips' lateral restraint barely stiffens
    // it), pulled quasi-statically: the stress reaches ft in ten times the time a wave takes to
    // cross the bar. The bonds across the middle are 5 % weaker, so the peak is 0.95 ft.
    // A bar longer than about twice its characteristic length E Gf / ft^2 stores more elastic
    // energy than its crack can take and snaps back, so that the energy balance cannot isolate
    // Gf: wood's (20 mm along the grain, 24 mm across) is measured on a bar 3 cm long (which
    // the grips stiffen by 6-11 %, so not its E). Glass (0.28 mm) is 4 x 2 x 2 mm, a voxel under
    // twice that so it can soften, and snaps back all the same (as glass does): only its E and
    // ft are checked.
    const double notch = 0.95;
    for (const auto& [name, material] : presetsInTension()) {
        const bool glass = name == "glass";
        const TensionTarget target = tensionTargetOf(material);
        BarSpec spec;
        spec.material = material;
        spec.sideM = glass ? 0.002 : 0.02;
        spec.lengthM = (glass ? 2 : 4) * spec.sideM;
        const double strainAtPeak = target.tensileStrengthPa / target.youngsModulusPa;
        spec.pullMS = strainAtPeak * std::sqrt(target.youngsModulusPa / material.densityKgM3) / 10;
        spec.notch = notch;
        const double characteristicM = target.youngsModulusPa * target.fractureEnergyJPerM2 / (target.tensileStrengthPa * target.tensileStrengthPa);
        BarSpec crackSpec = spec;
        if (!glass && spec.lengthM > 2 * characteristicM) crackSpec.lengthM = 1.5 * spec.sideM;
        for (const int perSide : {4, 8}) {
            spec.h = crackSpec.h = spec.sideM / perSide;
            const BarPull pull = pullBarApart(spec);
            const BarPull crack = crackSpec.lengthM == spec.lengthM ? pull : pullBarApart(crackSpec);
            const double gfJ = target.fractureEnergyJPerM2 * spec.sideM * spec.sideM, ft = notch * target.tensileStrengthPa;
            std::printf("%-21s h = %.5f m: E %+.1f %%, ft %+.1f %%, Gf %+.1f %% (bar %.0f mm); %d of %d bonds across broken, %d damaged elsewhere\n",
                        name.c_str(), spec.h, 100 * (pull.youngsModulusPa / target.youngsModulusPa - 1), 100 * (pull.peakStressPa / ft - 1),
                        100 * (crack.dissipatedJ / gfJ - 1), 1e3 * crackSpec.lengthM, pull.broken, pull.across, pull.damagedElsewhere);
            EXPECT_NEAR(pull.youngsModulusPa, target.youngsModulusPa, 0.05 * target.youngsModulusPa) << name << " h " << spec.h;
            EXPECT_NEAR(pull.peakStressPa, ft, 0.10 * ft) << name << " h " << spec.h;
            EXPECT_EQ(pull.broken, pull.across) << name << " h " << spec.h;
            EXPECT_EQ(crack.broken, crack.across) << name << " h " << spec.h;
            if (!glass) {
                EXPECT_NEAR(crack.dissipatedJ, gfJ, 0.10 * gfJ) << name << " h " << spec.h;
            }
        }
    }
}

TEST(Lattice, BondsTooLargeToSoftenStillDissipateTheFractureEnergy)
{
    // Glass softens only below h = 2 E Gf / ft² = 0.55 mm; above it a bond snaps at its peak and
    // would take its whole elastic energy with it, ft² h / 2E per area (nine times Gf at 5 mm).
    // Released into its particles, each crack takes Gf per area at any h. A glass bar pulled to
    // its strength stores far more than one crack takes, and shatters (as glass does): the
    // energy balance (work on the grips less kinetic and strain energy, no viscosity, so nothing
    // else dissipates) is then Gf times the faces of all the bonds that broke.
    Material glass = findMaterialPreset("glass");
    glass.strengthRateLaw = StrengthRateLaw::None;
    for (const double h : {0.005, 0.0025}) {
        BarSpec spec;
        spec.material = glass;
        spec.h = h;
        spec.sideM = 0.02;
        spec.lengthM = 0.08;
        spec.pullMS = glass.tensileStrengthPa / glass.youngsModulusPa * std::sqrt(glass.youngsModulusPa / glass.densityKgM3) / 10;
        spec.notch = 0.95;
        spec.bulkViscosity = 0.0;
        const BarPull pull = pullBarApart(spec);
        const double crackAreaM2 = pull.brokenAnywhere * h * h, gfJ = glass.fractureEnergyJPerM2 * crackAreaM2;
        const double snapJ = glass.tensileStrengthPa * glass.tensileStrengthPa * h / (2 * glass.youngsModulusPa) * crackAreaM2;
        std::printf("glass bar, h = %.4f m: %d bonds broken (%d of %d across the notch); dissipated %.4f J, Gf x their faces %.4f J (%+.1f %%), "
                    "their whole elastic energy at the peak %.4f J\n",
                    h, pull.brokenAnywhere, pull.broken, pull.across, pull.dissipatedJ, gfJ, 100 * (pull.dissipatedJ / gfJ - 1), snapJ);
        EXPECT_EQ(pull.broken, pull.across) << "h = " << h;
        EXPECT_NEAR(pull.dissipatedJ, gfJ, 0.4 * gfJ) << "h = " << h;
    }
}

TEST(Lattice, DavisonStevensDissipatesTheFractureEnergyWhenSlowAndHoldsMoreWhenFast)
{
    // Davison–Stevens on the bonds' stresses (B = 300 1/s, C = 1/ft). Pulled slowly (0.5 mm/s)
    // the crack opens over about 0.2 s, slowly for B, so the energy it takes is Gf (the peak
    // is higher than the softening line's all the same: before the crack localises every bond
    // must soften within the 6 ms the bar takes to reach its strength). Pulled at 5 cm/s damage
    // lags far behind: the bar carries more, and the crack takes more energy than Gf.
    const double expectedJ = kConcrete.fractureEnergyJPerM2 * 0.02 * 0.02, h = 0.01;
    BarSpec spec;
    spec.h = h;
    spec.law = LatticeDamageLaw::DavisonStevens;
    spec.pullMS = 5e-4;
    const BarPull slow = pullBarApart(spec);
    spec.pullMS = 0.05;
    const BarPull fast = pullBarApart(spec);
    spec.law = LatticeDamageLaw::Softening;
    const BarPull softening = pullBarApart(spec);
    std::printf("Davison-Stevens, 0.5 mm/s: dissipated %.4f J, Gf x area %.4f J (%+.1f %%), peak %.2f MPa; 5 cm/s: %.4f J, peak %.2f MPa "
                "(softening line: %.2f MPa)\n",
                slow.dissipatedJ, expectedJ, 100 * (slow.dissipatedJ / expectedJ - 1), slow.peakStressPa / 1e6, fast.dissipatedJ,
                fast.peakStressPa / 1e6, softening.peakStressPa / 1e6);
    EXPECT_EQ(slow.broken, slow.across);
    EXPECT_EQ(slow.damagedElsewhere, 0);
    EXPECT_NEAR(slow.dissipatedJ, expectedJ, 0.10 * expectedJ);
    EXPECT_GT(fast.peakStressPa, 1.2 * softening.peakStressPa);
    EXPECT_GT(fast.dissipatedJ, 1.2 * slow.dissipatedJ);
}

TEST(Lattice, SpallStartsWhereOneDimensionalWaveTheoryPutsIt)
{
    // A triangular compressive pulse (instant rise to σp, linear decay over T) runs along a bar
    // to its free rear face and reflects as tension. One-dimensional wave theory: at depth x from
    // the rear face the net tension is σp · 2x / λ (λ = c T the pulse's length), so the first
    // spall is where that reaches the tensile strength, x = ft λ / (2 σp) (e.g. Kolsky, Stress
    // Waves in Solids, 1953; Zukas et al., Impact Dynamics, 1982, ch. 4). Here λ = 40 voxels and
    // σp = 4, 3 and 2.5 ft: 5, 6.7 and 8 voxels deep, beyond the 4-voxel front the lattice needs
    // (a jump rings; the theory's jump is idealised too). With the default bulk viscosity. The bar is 4 × 4 voxels across and 120 long: far longer
    // pulses than its thickness travel at the bar speed.
    const int length = 120, side = 4;
    for (const double peakOverStrength : {4.0, 3.0, 2.5}) {
        Lattice lattice = latticeOfBox(length, side, side);
        const double c = barWaveSpeed(kConcrete), dt = lattice.stableTimeStepS();
        const double peakPa = peakOverStrength * kConcrete.tensileStrengthPa, pulseS = 40.0 * kH / c;
        const double expectedDepthM = kConcrete.tensileStrengthPa * c * pulseS / (2.0 * peakPa);
        const double faceForceN = peakPa * kH * kH;  // per particle of the loaded face
        int firstDamagedLayer = -1;
        for (double t = 0.0; t < (length + 60) * kH / c && firstDamagedLayer < 0; t += dt) {
            const double riseS = 4.0 * kH / c;  // a front over 4 voxels: a lattice cannot carry a jump without ringing
            const double pressure = t < riseS ? faceForceN * t / riseS : t < pulseS ? faceForceN * (1.0 - (t - riseS) / (pulseS - riseS)) : 0.0;
            for (size_t p = 0; p < lattice.particleCount(); ++p)
                lattice.externalForceN[p] = Eigen::Vector3d(lattice.model().voxel[p].x() == 0 ? pressure : 0.0, 0, 0);
            lattice.step(dt);
            for (size_t b = 0; b < lattice.bondCount(); ++b)
                if (lattice.model().bonds[b].axis == 0 && lattice.bondDamage(b) > 0.0)
                    firstDamagedLayer = std::max(firstDamagedLayer, lattice.model().voxel[lattice.model().bonds[b].low].x());
        }
        ASSERT_GE(firstDamagedLayer, 0) << "nothing failed";
        // The bond between layers i and i + 1 lies (length - 1 - i) voxels from the rear face.
        const double depthM = (length - 1 - firstDamagedLayer) * kH;
        std::printf("spall at peak %.1f ft: first failure %.1f cm from the rear face, 1-D wave theory %.1f cm (%+.0f %%)\n", peakOverStrength,
                    100 * depthM, 100 * expectedDepthM, 100 * (depthM / expectedDepthM - 1));
        EXPECT_NEAR(depthM, expectedDepthM, 0.25 * expectedDepthM);
    }
}

TEST(Lattice, DirectShearFollowsTheMohrCoulombEnvelope)
{
    // A direct shear test (as a shear box or van der Pluijm's couplet test): two layers of
    // voxels, the lower held still, the upper held and moved, first down to a compression (or
    // up, to a tension), then sideways at 1 mm/s until the bonds between them start to give. The
    // shear stress on the upper layer then (its bonds' force over its area) must follow
    // Mohr–Coulomb, τ = c + μ σ, with σ the compression measured on the same layer; under a
    // tension of 0.6 ft the ellipse joining the cut-off to pure shear, τ = c √(1 − 0.6²).
    Material material = kConcrete;
    material.shearStrengthPa = 4e6;
    material.frictionCoefficient = 0.7;
    const int side = 4;
    const double areaM2 = side * side * kH * kH;
    for (const double compressionOverCohesion : {-0.6 * material.tensileStrengthPa / material.shearStrengthPa, 0.0, 1.0, 2.5}) {
        Body body = test::boxBody(side, side, 2, kH, material.densityKgM3);
        for (auto it = body.grid->tree().beginValueOn(); it; ++it) it.setValue(*it | kAnchorBit);
        Lattice lattice = Lattice::fromBody(body, material);
        // Everything is held: the state is quasi-static, with no wave to wait for. Two layers of
        // particles, each with one bond across: the normal stiffness is kn/h + 2λ.
        const double pressDownM = compressionOverCohesion * material.shearStrengthPa * kH /
                                  (lattice.model().stiffness.normalNPerM[2] / kH + 2.0 * lattice.model().stiffness.lameLambdaPa);
        const double liftM = compressionOverCohesion < 0.0 ? 0.6 * lattice.model().stiffness.strength[0].peakStretchM : 0.0;
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.model().voxel[p].z() == 1) lattice.state.positionM[p].z() += compressionOverCohesion < 0.0 ? liftM : -pressDownM;
        lattice.refreshForces();
        auto upperLayerStressPa = [&]() -> Eigen::Vector3d {
            Eigen::Vector3d force = Eigen::Vector3d::Zero();
            for (size_t p = 0; p < lattice.particleCount(); ++p)
                if (lattice.model().voxel[p].z() == 1) force += lattice.state.bondForceN[p];
            return force / areaM2;
        };
        const double compressionPa = upperLayerStressPa().z();
        const double shearMS = 1e-3, dt = lattice.stableTimeStepS();
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.model().voxel[p].z() == 1) lattice.state.velocityMS[p] = Eigen::Vector3d(shearMS, 0, 0);
        // The failure surface is where damage starts: the shear stress of the last step before.
        double onsetShearPa = 0.0;
        auto damaged = [&] {
            for (size_t b = 0; b < lattice.bondCount(); ++b)
                if (lattice.bondDamage(b) > 0.0) return true;
            return false;
        };
        for (int i = 0; i < 200000 && !damaged(); ++i) {
            onsetShearPa = -upperLayerStressPa().x();
            lattice.step(dt);
        }
        const double expectedPa = liftM > 0.0 ? material.shearStrengthPa * std::sqrt(1.0 - 0.36)
                                              : material.shearStrengthPa + material.frictionCoefficient * compressionPa;
        std::printf("direct shear at sigma = %.2f MPa: tau at the onset of damage %.3f MPa, Mohr-Coulomb %.3f MPa (%+.2f %%)\n",
                    compressionPa / 1e6, onsetShearPa / 1e6, expectedPa / 1e6, 100 * (onsetShearPa / expectedPa - 1));
        if (liftM == 0.0) {
            EXPECT_GE(compressionPa, 0.9 * compressionOverCohesion * material.shearStrengthPa);
        }
        EXPECT_NEAR(onsetShearPa, expectedPa, 0.01 * expectedPa);
    }
}

TEST(Lattice, ConcreteIsStrongerWhenPulledFaster)
{
    // A concrete bar (4 × 2 × 2 voxels, both end layers held) pulled apart at strain rates of
    // 0.01, 1 and 3 1/s, with the fib Model Code's rate law and without: the ratio of the peak
    // stresses must be the Model Code's dynamic increase factor for tension at that rate, by
    // hand 1e4^0.018 = 1.180, 1e6^0.018 = 1.282 and 3e6^0.018 = 1.308 (fib Model Code 2010 eq.
    // 5.1-108, ε̇0 = 1e-6 1/s), within 5 %: as the rate rises, the stress a substep adds
    // (E ε̇ dt, 1.4 % of ft at 3 1/s), the bar's inertia and the undamped ringing of the bending
    // its held grips put into the bonds at their corners blur the peaks (faster than about
    // 10 1/s the bar breaks within a few of its wave transits and inertia sets its peak).
    const std::pair<double, double> rateAndFactor[] = {{1e-2, 1.180}, {1.0, 1.282}, {3.0, 1.308}};
    auto peakStressPa = [](double ratePerS, StrengthRateLaw law) {
        Material material = kConcrete;
        material.strengthRateLaw = law;
        const int nx = 4;
        Body body = test::boxBody(nx, 2, 2, kH, material.densityKgM3);
        for (auto it = body.grid->tree().beginValueOn(); it; ++it)
            if (it.getCoord().x() == 0 || it.getCoord().x() == nx - 1) it.setValue(*it | kAnchorBit);
        Lattice lattice = Lattice::fromBody(body, material, StaticWorld(), withoutBulkViscosity());
        double x0 = lattice.state.positionM[0].x();
        for (const Eigen::Vector3d& x : lattice.state.positionM) x0 = std::min(x0, x.x());
        // From rest length on the velocity field of a uniform strain rate, so no wave runs ahead.
        for (size_t p = 0; p < lattice.particleCount(); ++p) lattice.state.velocityMS[p] = Eigen::Vector3d(ratePerS * (lattice.state.positionM[p].x() - x0), 0, 0);
        const double dt = lattice.stableTimeStepS();
        const double areaM2 = 4 * kH * kH;
        double peakPa = 0.0;
        for (int i = 0; i < 2000000; ++i) {
            lattice.step(dt);
            double forceN = 0.0;
            for (size_t p = 0; p < lattice.particleCount(); ++p)
                if (lattice.model().voxel[p].x() == nx - 1) forceN -= lattice.state.bondForceN[p].x();
            peakPa = std::max(peakPa, forceN / areaM2);
            if (forceN / areaM2 < 0.5 * peakPa) break;
        }
        return peakPa;
    };
    for (const auto& [ratePerS, factor] : rateAndFactor) {
        const double withLaw = peakStressPa(ratePerS, StrengthRateLaw::FibModelCode2010), without = peakStressPa(ratePerS, StrengthRateLaw::None);
        const double ratio = withLaw / without;
        std::printf("pulled at %g 1/s: peak stress x %.3f of the rate-free lattice's, fib DIF %.3f (%+.1f %%)\n", ratePerS, ratio, factor,
                    100 * (ratio / factor - 1));
        EXPECT_NEAR(ratio, factor, 0.05 * factor) << ratePerS << " 1/s";
    }
}

TEST(Masonry, BondPatternsTieTheLeavesAndStaggerTheirHeadJoints)
{
    // A one-brick wall, 215 mm thick: two leaves of 102.5 mm and a 10 mm collar joint between.
    // Running bond leaves the leaves apart in every course (a collar joint right through the
    // wall); English bond ties them in every other course (headers across the wall); Flemish
    // bond at every header, a third of each course (112.5 of every 337.5 mm). In every pattern
    // the head joints of one course lie at least a quarter brick (56 mm) from those of the
    // course below: no straight joint runs up the wall.
    Material m = findMaterialPreset("brick-masonry");
    const double frontM = 0.05, backM = 0.16, stepM = 0.001;
    for (const auto& [pattern, tiedShare] : {std::pair{BondPattern::Running, 0.0}, std::pair{BondPattern::English, 0.5},
                                             std::pair{BondPattern::Flemish, 1.0 / 3.0}}) {
        m.bondPattern = pattern;
        int tied = 0, samples = 0;
        double closestJointsM = 1e9;
        std::vector<double> jointsBelow;
        for (int course = 0; course < 4; ++course) {
            const double z = course * 0.075 + 0.03;
            std::vector<double> joints;
            for (double along = 0.0; along < 4.05; along += stepM) {
                tied += masonryUnitOf(m, along, frontM, z) == masonryUnitOf(m, along, backM, z);
                ++samples;
                if (masonryUnitOf(m, along, frontM, z) != masonryUnitOf(m, along + stepM, frontM, z)) joints.push_back(along);
            }
            for (const double a : joints)
                for (const double b : jointsBelow) closestJointsM = std::min(closestJointsM, std::abs(a - b));
            jointsBelow = joints;
        }
        std::printf("%s bond: leaves tied over %.3f of the wall's length, head joints of adjacent courses at least %.1f mm apart\n",
                    enumName(pattern).c_str(), double(tied) / samples, 1e3 * closestJointsM);
        EXPECT_NEAR(double(tied) / samples, tiedShare, 0.01) << enumName(pattern);
        EXPECT_GT(closestJointsM, 0.050) << enumName(pattern);
    }
}

TEST(Lattice, MasonryPulledAcrossItsBedJointsBreaksInAJointAtTheJointsStrength)
{
    // Brick masonry is bricks in mortar (issue 18): a prism of three courses (2.5 cm voxels, a
    // course is 75 mm: three voxels) pulled slowly across its bed joints must open one bed joint
    // at the unit–mortar bond's tensile strength (0.3 MPa; the bricks' 2.0 MPa is far above),
    // breaking no bond inside a brick.
    const Material material = findMaterialPreset("brick-masonry");
    ASSERT_TRUE(hasUnits(material));
    const double h = 0.025, sideM = 0.1, pullMS = 0.005;
    const int n = 4, courses = 3, nz = 3 * courses;
    Body body = test::boxBody(n, n, nz, h, material.densityKgM3);
    for (auto it = body.grid->tree().beginValueOn(); it; ++it)
        if (it.getCoord().z() == 0 || it.getCoord().z() == nz - 1) it.setValue(*it | kAnchorBit);
    Lattice lattice = Lattice::fromBody(body, material);
    int unitBonds = 0;
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        const LatticeBond& bond = lattice.model().bonds[b];
        const bool acrossBedJoint = bond.axis == 2 && lattice.model().voxel[bond.low].z() % 3 == 2;
        EXPECT_EQ(bond.strengthClass == 0, acrossBedJoint) << "bond " << b << ": a bed joint lies between every third layer";
        unitBonds += bond.strengthClass;
    }
    const double z0 = lattice.state.positionM[0].z();
    for (size_t p = 0; p < lattice.particleCount(); ++p)
        lattice.state.velocityMS[p] = lattice.model().voxel[p].z() == 0 ? Eigen::Vector3d::Zero()
                                                          : Eigen::Vector3d(0, 0, pullMS * (lattice.state.positionM[p].z() - z0) / ((nz - 1) * h));
    const double dt = lattice.stableTimeStepS();
    double peakStressPa = 0.0;
    for (double t = 0.0; t < 1.5 * lattice.model().stiffness.strength[0].zeroTractionStretchM / pullMS; t += dt) {
        lattice.step(dt);
        double pullN = 0.0;
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.model().voxel[p].z() == nz - 1) pullN -= lattice.state.bondForceN[p].z();
        peakStressPa = std::max(peakStressPa, pullN / (sideM * sideM));
    }
    int brokenInJoints = 0, brokenInUnits = 0;
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (lattice.bondDamage(b) == 1.0) (lattice.model().bonds[b].strengthClass ? brokenInUnits : brokenInJoints) += 1;
    std::printf("masonry prism pulled across its bed joints: peak %.3f MPa, joint strength %.3f MPa (%+.1f %%); bonds broken: %d in joints, "
                "%d in bricks (of %d bonds, %d inside bricks)\n",
                peakStressPa / 1e6, material.tensileStrengthPa / 1e6, 100 * (peakStressPa / material.tensileStrengthPa - 1), brokenInJoints,
                brokenInUnits, int(lattice.bondCount()), unitBonds);
    EXPECT_NEAR(peakStressPa, material.tensileStrengthPa, 0.10 * material.tensileStrengthPa);
    EXPECT_EQ(brokenInJoints, n * n) << "one bed joint opens right through";
    EXPECT_EQ(brokenInUnits, 0);
    // Voxels taller than a course (75 mm) do not resolve the bricks: every bond is a joint's.
    const Lattice coarse = Lattice::fromBody(test::boxBody(6, 3, 4, 0.1, material.densityKgM3), material);
    for (const LatticeBond& bond : coarse.model().bonds) EXPECT_EQ(bond.strengthClass, 0);
}

TEST(Lattice, StrengthScatterHasTheMaterialsMeanCovAndCorrelation)
{
    // The field: zero mean, unit variance and correlation exp(-1/2) at one correlation length,
    // over 8 seeds x 500 points 5 lengths apart.
    const double l = 0.02;
    double sum = 0, squares = 0, lagged = 0;
    int n = 0;
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        const GaussianRandomField field(seed, l);
        for (int i = 0; i < 500; ++i) {
            const Eigen::Vector3d x(5 * l * (i % 10), 5 * l * ((i / 10) % 10), 5 * l * (i / 100));
            const double g = field.at(x);
            sum += g;
            squares += g * g;
            lagged += g * field.at(x + Eigen::Vector3d(l, 0, 0));
            ++n;
        }
    }
    std::printf("field: mean %.3f, variance %.3f, correlation at one length %.3f (exp(-1/2) = %.3f)\n", sum / n, squares / n, lagged / n,
                std::exp(-0.5));
    EXPECT_NEAR(sum / n, 0.0, 0.05);
    EXPECT_NEAR(squares / n, 1.0, 0.1);
    EXPECT_NEAR(lagged / n, std::exp(-0.5), 0.08);

    // The variance function against its integral done numerically, and its two limits.
    for (const double t : {0.3 * l, l, 4 * l}) {
        double integral = 0;
        const int steps = 100000;
        for (int i = 0; i < steps; ++i) {
            const double tau = (i + 0.5) * t / steps;
            integral += (t - tau) * std::exp(-tau * tau / (2 * l * l)) * t / steps;
        }
        EXPECT_NEAR(varianceFunction(t, l), 2 * integral / (t * t), 1e-6) << t;
    }
    EXPECT_DOUBLE_EQ(varianceFunction(0.0, l), 1.0);
    EXPECT_NEAR(varianceFunction(1000 * l, l), std::sqrt(2 * M_PI) / 1000, 1e-5);

    // The concrete preset's bonds at 5 mm: mean 1, CoV 0.18 times the face's reduction; the same
    // seed gives the same bonds, another seed others.
    const Material concrete = findMaterialPreset("concrete");
    const double h = 0.005;
    const Body body = test::boxBody(20, 20, 20, h, concrete.densityKgM3);
    LatticeSettings seed3, seed4;
    seed3.seed = 3;
    seed4.seed = 4;
    const Lattice a = Lattice::fromBody(body, concrete, StaticWorld(), seed3), again = Lattice::fromBody(body, concrete, StaticWorld(), seed3),
                  other = Lattice::fromBody(body, concrete, StaticWorld(), seed4);
    double mean = 0, meanSquare = 0;
    size_t same = 0, differ = 0;
    for (size_t b = 0; b < a.bondCount(); ++b) {
        const double s = a.state.bondHistory[b].strengthScale;
        mean += s / a.bondCount();
        meanSquare += s * s / a.bondCount();
        same += s == again.state.bondHistory[b].strengthScale;
        differ += s != other.state.bondHistory[b].strengthScale;
    }
    const double cov = std::sqrt(meanSquare - mean * mean) / mean, expected = concrete.strengthCoefficientOfVariation * varianceFunction(h, 0.016);
    std::printf("concrete bonds at h = %.3f m: mean strength scale %.3f, CoV %.3f (expected %.3f)\n", h, mean, cov, expected);
    EXPECT_NEAR(mean, 1.0, 0.03);
    EXPECT_NEAR(cov, expected, 0.15 * expected);
    EXPECT_EQ(same, a.bondCount());
    EXPECT_EQ(differ, a.bondCount());
}
