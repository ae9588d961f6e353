// The lattice of materials with structure, against their presets and published data: wood's
// elasticity along and across the grain, masonry's bond patterns and joints, and the strength
// scatter's statistics.
#include "LatticeTestUtil.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>
#include <spall/lattice/RandomField.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <tuple>

using namespace spall;
using namespace spall::test;

TEST(Lattice, WoodsLatticeHasItsElasticityAlongAndAcrossTheGrain)
{
    // The normal stiffness of a lattice with a grain along z, diag(kn/h) + λ 1 1ᵀ: its inverse
    // (computed here by Eigen, not by the calibration's closed form) must give the preset's E
    // along and across the grain and ν across it. (Its shear moduli: the next test, by straining
    // a lattice.)
    const Material& wood = findMaterialPreset("wood");
    ASSERT_EQ(wood.grainAxis, GrainAxis::Z);
    const LatticeStiffness k = calibrateLattice(wood, kH);
    Eigen::Matrix3d normal = Eigen::Matrix3d::Constant(k.lameLambdaPa);
    for (int axis = 0; axis < 3; ++axis) normal(axis, axis) += k.normalNPerM[axis] / kH;
    const Eigen::Matrix3d compliance = normal.inverse();
    EXPECT_NEAR(1.0 / compliance(2, 2), wood.alongGrainYoungsModulusPa, 1e-9 * wood.alongGrainYoungsModulusPa);
    EXPECT_NEAR(1.0 / compliance(0, 0), wood.youngsModulusPa, 1e-9 * wood.youngsModulusPa);
    EXPECT_NEAR(-compliance(0, 1) / compliance(0, 0), wood.poissonRatio, 1e-9);
    // Reciprocity of a symmetric compliance: ν_TL / ν_LT = E_T / E_L (Wood Handbook ch. 5).
    const double nuAlongToAcross = -compliance(2, 0) / compliance(2, 2), nuAcrossToAlong = -compliance(0, 2) / compliance(0, 0);
    std::printf("wood: nu_LT %.3f, nu_TL %.4f\n", nuAlongToAcross, nuAcrossToAlong);
    EXPECT_NEAR(nuAcrossToAlong / nuAlongToAcross, wood.youngsModulusPa / wood.alongGrainYoungsModulusPa, 1e-9);
    EXPECT_EQ(k.strength[1].youngsModulusPa, wood.alongGrainYoungsModulusPa);
}

namespace {

/// The shear modulus of a lattice of `material` (10³ voxels, h = kH) in the plane (i, j): every
/// particle placed on the uniform strain γ_ij = γ (each axis turned by γ/2 towards the other:
/// pure shear, no rotation), held there, its rotation free to relax (stepped, a particle's spin
/// stopped whenever it turns against the moment on it); the energy of the bonds of the inner
/// 4³ voxels, away from the surfaces, over their volume is ½ G γ².
double shearModulusOfLattice(const Material& material, int i, int j)
{
    const int n = 10;
    Lattice lattice = Lattice::fromBody(test::boxBody(n, n, n, kH, material.densityKgM3), material, StaticWorld(), withoutBulkViscosity());
    const double gamma = 1e-4;
    std::vector<Eigen::Vector3d> strained = lattice.state.positionM;
    for (Eigen::Vector3d& x : strained) {
        const Eigen::Vector3d x0 = x;
        x[i] += 0.5 * gamma * x0[j];
        x[j] += 0.5 * gamma * x0[i];
    }
    const double dt = lattice.stableTimeStepS();
    for (int step = 0; step < 1500; ++step) {
        lattice.state.positionM = strained;
        for (Eigen::Vector3d& v : lattice.state.velocityMS) v.setZero();
        lattice.refreshForces();
        lattice.step(dt);
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.state.angularVelocityRadS[p].dot(lattice.state.bondMomentNm[p]) < 0.0) lattice.state.angularVelocityRadS[p].setZero();
    }
    lattice.state.positionM = strained;
    lattice.refreshForces();
    const auto inner = [&](const openvdb::Coord& v) { return v.x() >= 3 && v.x() < n - 3 && v.y() >= 3 && v.y() < n - 3 && v.z() >= 3 && v.z() < n - 3; };
    double energyJ = 0.0;
    for (size_t b = 0; b < lattice.bondCount(); ++b)
        if (inner(lattice.model().voxel[lattice.model().bonds[b].low])) energyJ += lattice.bondStrainEnergyJ(b);
    const double volumeM3 = std::pow((n - 6) * kH, 3);
    return 2.0 * energyJ / (volumeM3 * gamma * gamma);
}

}  // namespace

TEST(Lattice, WoodsLatticeShearedHasThePresetsShearModuliWithItsRotationsFree)
{
    // Wood with its grain along z: G in the planes that hold the grain (xz, yz) is the preset's
    // G_LT, 0.625 GPa (Wood Handbook table 5-1), in the plane across it (xy) E_T / 2(1 + ν) =
    // 0.222 GPa. Issue 47's audit found 0.365 GPa in xz when each bond had one shear spring for
    // both its directions: relaxed rotations put the plane's two springs in series. Concrete's
    // isotropic G = E / 2(1 + ν) in every plane is the control. Within 2 %.
    const Material& wood = findMaterialPreset("wood");
    ASSERT_EQ(wood.grainAxis, GrainAxis::Z);
    const double acrossPa = wood.youngsModulusPa / (2 * (1 + wood.poissonRatio));
    const double concretePa = kConcrete.youngsModulusPa / (2 * (1 + kConcrete.poissonRatio));
    const std::tuple<const char*, const Material*, int, int, double> cases[] = {{"wood xz", &wood, 0, 2, wood.alongGrainShearModulusPa},
                                                                                 {"wood yz", &wood, 1, 2, wood.alongGrainShearModulusPa},
                                                                                 {"wood xy", &wood, 0, 1, acrossPa},
                                                                                 {"concrete xz", &kConcrete, 0, 2, concretePa}};
    for (const auto& [name, material, i, j, expectedPa] : cases) {
        const double measuredPa = shearModulusOfLattice(*material, i, j);
        std::printf("%s: G %.4g GPa, expected %.4g GPa (%+.2f %%)\n", name, measuredPa / 1e9, expectedPa / 1e9, 100 * (measuredPa / expectedPa - 1));
        EXPECT_NEAR(measuredPa, expectedPa, 0.02 * expectedPa) << name;
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
    // breaking no bond inside a brick. Every bond alike (the scatter has its own tests).
    const Material material = test::withoutStrengthScatter(findMaterialPreset("brick-masonry"));
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
    // Voxels taller than a course (75 mm) do not resolve the bricks: a bond across the bed
    // joints is a joint's, one across the courses homogenised masonry's
    // (test_lattice_masonry.cpp).
    const Lattice coarse = Lattice::fromBody(test::boxBody(6, 3, 4, 0.1, material.densityKgM3), material);
    for (const LatticeBond& bond : coarse.model().bonds) EXPECT_EQ(bond.strengthClass, bond.axis == 2 ? 0 : 1);
}

TEST(Lattice, StrengthScatterFieldOnAGridIsTheFieldsCosineSum)
{
    // The tables' products against the cosines summed directly, at grid points spread over a
    // box with negative and positive indices and an odd step.
    const GaussianRandomField field(7, 0.03);
    const double stepM = 0.0125;
    const GaussianRandomFieldOnGrid grid(field, stepM, Eigen::Vector3i(-40, -3, 0), Eigen::Vector3i(90, 17, 400));
    double worst = 0.0;
    for (int i = 0; i < 2000; ++i) {
        const Eigen::Vector3i n(-40 + (i * 37) % 131, -3 + (i * 11) % 21, (i * 101) % 401);
        worst = std::max(worst, std::abs(grid.at(n) - field.at(stepM * n.cast<double>())));
    }
    std::printf("largest difference from the cosine sum: %.2e\n", worst);
    EXPECT_LT(worst, 1e-11);
}

TEST(Lattice, StrengthScatterFieldHasUnitVarianceAndItsCorrelation)
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
}

namespace {

/// The mean and CoV of the strength scales of the bonds `picks` chooses, pooled over the
/// lattices that seeds 1-8 give a body: one body spans only so many correlation lengths, and
/// its own mean strays from 1 by the field's average over it.
template <class Picks>
std::pair<double, double> strengthScaleMeanAndCov(const Body& body, const Material& material, const Picks& picks)
{
    double sum = 0, squares = 0;
    size_t n = 0;
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        const Lattice lattice = Lattice::fromBody(body, material, StaticWorld(), LatticeSettings(), VoxelBlocks(), seed);
        for (size_t b = 0; b < lattice.bondCount(); ++b) {
            if (!picks(lattice.model().bonds[b])) continue;
            const double s = lattice.state.bondHistory[b].strengthScale;
            sum += s;
            squares += s * s;
            ++n;
        }
    }
    const double mean = sum / double(n);
    return {mean, std::sqrt(squares / double(n) - mean * mean) / mean};
}

}  // namespace

TEST(Lattice, MasonrysJointsAndUnitsScatterEachByTheirOwnCov)
{
    // The brick preset resolved (1 cm): its joints' bonds and its units' each have mean 1 and
    // their own CoV, reduced by the face's averaging, from fields of their own; coarser than a
    // course, every bond (joints', homogenised) follows the joints'.
    const Material brick = findMaterialPreset("brick-masonry");
    ASSERT_GT(brick.strengthCoefficientOfVariation, 0.0);
    ASSERT_GT(brick.unitStrengthCoefficientOfVariation, 0.0);
    const double h = 0.01, gamma = varianceFunction(h, brick.strengthCorrelationLengthM);
    const Body wall = test::boxBody(120, 10, 60, h, brick.densityKgM3);
    const auto [jointMean, jointCov] = strengthScaleMeanAndCov(wall, brick, [](const LatticeBond& b) { return b.strengthClass == 0; });
    const auto [unitMean, unitCov] = strengthScaleMeanAndCov(wall, brick, [](const LatticeBond& b) { return b.strengthClass == 1; });
    std::printf("brick at %.2f m: joints' bonds mean %.3f CoV %.3f (expected %.3f); units' mean %.3f CoV %.3f (expected %.3f)\n", h, jointMean,
                jointCov, brick.strengthCoefficientOfVariation * gamma, unitMean, unitCov, brick.unitStrengthCoefficientOfVariation * gamma);
    EXPECT_NEAR(jointMean, 1.0, 0.05);
    EXPECT_NEAR(unitMean, 1.0, 0.05);
    EXPECT_NEAR(jointCov, brick.strengthCoefficientOfVariation * gamma, 0.15 * brick.strengthCoefficientOfVariation * gamma);
    EXPECT_NEAR(unitCov, brick.unitStrengthCoefficientOfVariation * gamma, 0.15 * brick.unitStrengthCoefficientOfVariation * gamma);

    const double coarseH = 0.1, coarseGamma = varianceFunction(coarseH, brick.strengthCorrelationLengthM);
    const auto [coarseMean, coarseCov] =
        strengthScaleMeanAndCov(test::boxBody(40, 3, 25, coarseH, brick.densityKgM3), brick, [](const LatticeBond&) { return true; });
    std::printf("brick at %.2f m: every bond mean %.3f CoV %.3f (the joints', expected %.3f)\n", coarseH, coarseMean, coarseCov,
                brick.strengthCoefficientOfVariation * coarseGamma);
    EXPECT_NEAR(coarseMean, 1.0, 0.05);
    EXPECT_NEAR(coarseCov, brick.strengthCoefficientOfVariation * coarseGamma, 0.15 * brick.strengthCoefficientOfVariation * coarseGamma);
}

TEST(Lattice, StrengthScatterHasTheMaterialsMeanAndCovAndFollowsTheSeed)
{
    // The concrete preset's bonds at 5 mm: mean 1, CoV 0.18 times the face's reduction; the same
    // seed gives the same bonds, another seed others.
    const Material concrete = findMaterialPreset("concrete");
    const double h = 0.005;
    const Body body = test::boxBody(20, 20, 20, h, concrete.densityKgM3);
    const auto seeded = [&](uint64_t seed) { return Lattice::fromBody(body, concrete, StaticWorld(), LatticeSettings(), VoxelBlocks(), seed); };
    const Lattice a = seeded(3), again = seeded(3), other = seeded(4);
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
