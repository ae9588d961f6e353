// The deformable phase's lattice breaking, against what fracture mechanics and tests publish:
// the fracture energy a bar pulled apart dissipates at every voxel size and for every preset, the
// Mohr–Coulomb envelope in direct shear, spall depth from one-dimensional wave theory and the
// rate effect on strength.
#include "BarLoading.h"
#include "LatticeTestUtil.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>
#include <spall/lattice/RateDamage.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

using namespace spall;
using namespace spall::test;

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

TEST(Lattice, RateLawRaisesTheStrengthButNotTheFractureEnergyAtAnyVoxelSize)
{
    // The same bar with the fib Model Code 2010's rate law (eq. 5.1-108: the strength, not Gf),
    // pulled at 0.05 and 0.5 m/s (1.25 and 12.5 1/s over its 4 cm): the crack must take the same
    // energy per area at h, h/2 and h/4, within 10 % of each other, where a law that stretched
    // the whole softening line took 1.6–2.6 and 4.6–12.3 times Gf × area, growing as h fell
    // (issue 47's audit). The peak stress must still rise by the law's factor for the bar's
    // rate, by hand 1.25e6^0.018 = 1.288 and, past 10 1/s, 0.0062 × 12.5e6^(1/3) = 1.444, within
    // 10 % (the grips' stress concentration and the bar's inertia at 0.5 m/s).
    const double expectedJ = kConcrete.fractureEnergyJPerM2 * 0.02 * 0.02;
    const std::pair<double, double> pullAndFactor[] = {{0.05, 1.288}, {0.5, 1.444}};
    for (const auto& [pullMS, factor] : pullAndFactor) {
        std::vector<double> perGf;
        for (const int perCm : {1, 2, 4}) {
            BarSpec spec;
            spec.material.strengthRateLaw = StrengthRateLaw::FibModelCode2010;
            spec.h = 0.01 / perCm;
            spec.pullMS = pullMS;
            const BarPull pull = pullBarApart(spec);
            spec.material.strengthRateLaw = StrengthRateLaw::None;
            const double rateFreePeakPa = pullBarApart(spec).peakStressPa;
            perGf.push_back(pull.dissipatedJ / expectedJ);
            std::printf("%.2f m/s, h = %.4f m: dissipated %.3f x Gf x area; peak %.3f x the rate-free bar's (fib %.3f); %d of %d bonds "
                        "across broken\n", pullMS, spec.h, perGf.back(), pull.peakStressPa / rateFreePeakPa, factor, pull.broken, pull.across);
            EXPECT_EQ(pull.broken, pull.across) << pullMS << " m/s, h = " << spec.h;
            EXPECT_NEAR(pull.peakStressPa / rateFreePeakPa, factor, 0.10 * factor) << pullMS << " m/s, h = " << spec.h;
        }
        const auto [lowest, highest] = std::minmax_element(perGf.begin(), perGf.end());
        EXPECT_LT(*highest / *lowest - 1.0, 0.10) << pullMS << " m/s";
        EXPECT_NEAR(*highest, 1.0, 0.15) << pullMS << " m/s";
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
        Material m = withoutStrengthScatter(findMaterialPreset(name));
        m.strengthRateLaw = StrengthRateLaw::None;
        out.push_back({name, m});
    }
    out[1].first = "wood across the grain";
    Material alongGrain = out[1].second;
    alongGrain.grainAxis = GrainAxis::X;
    out.push_back({"wood along the grain", alongGrain});
    Material joints = withoutStrengthScatter(findMaterialPreset("brick-masonry"));
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

TEST(Lattice, GlassCracksAtItsWeakestLinkAsWeibullsLawSaysAtTwoVoxelSizes)
{
    // The glass preset's bonds are each the weakest link of their face (ASTM E1300's Weibull law,
    // m = 7, 45 MPa the median of 1 m^2). Bonds under one uniform tension then first crack, by
    // the same law at their summed area A, at a median of ft (A_ref / A)^(1/m), with a spread of
    // ln(stress) of pi / (m sqrt 6) (Weibull's). A glass bar 0.2 m long, 2 cm square, pulled
    // slowly over 32 seeds at h = 1 cm and 5 mm: its x-bonds carry the tension, those of the
    // grips' quarters 1.5 times as strong (so each counts 1.5^-7 of its area). The bar breaks
    // when the first crack runs: at once with 2 x 2 bonds across it, later with 4 x 4, whose
    // neighbours take a broken bond's load (the ratio is printed and bounded).
    const Material glass = findMaterialPreset("glass");
    const double m = glass.strengthWeibullModulus;
    for (const double h : {0.01, 0.005}) {
        BarSpec spec;
        spec.material = glass;
        spec.h = h;
        spec.lengthM = 0.2;
        spec.sideM = 0.02;
        spec.notch = 1.0;
        spec.watchFirstDamage = true;
        const int nx = int(std::lround(spec.lengthM / h)), ny = int(std::lround(spec.sideM / h));
        const int gripColumns = 2 * (nx / 4), middleColumns = nx - 1 - gripColumns;
        const double gaugeM = (nx - 1) * h, areaM2 = (middleColumns + gripColumns * std::pow(1.5, -m)) * ny * ny * h * h;
        const double medianPa = glass.tensileStrengthPa * std::pow(glass.strengthReferenceAreaM2 / areaM2, 1.0 / m);
        // To 1.6 times the median (the odds it holds beyond: exp(-ln 2 x 1.6^7) = 1e-8) in ten
        // times the wave's transit.
        const double waveMS = std::sqrt(glass.youngsModulusPa / glass.densityKgM3), endStrain = 1.6 * medianPa / glass.youngsModulusPa;
        spec.pullMS = endStrain * waveMS / 10.0;
        std::vector<double> logFirst;
        double peakOverFirst = 0.0;
        for (uint64_t seed = 1; seed <= 32; ++seed) {
            spec.seed = seed;
            const BarPull pull = loadBar(spec, endStrain * gaugeM / spec.pullMS, 0.1 * medianPa);
            logFirst.push_back(std::log(pull.firstDamageStressPa));
            peakOverFirst += pull.peakStressPa / pull.firstDamageStressPa / 32;
        }
        std::sort(logFirst.begin(), logFirst.end());
        const double median = std::exp(0.5 * (logFirst[15] + logFirst[16]));
        double mean = 0, squares = 0;
        for (const double l : logFirst) mean += l / 32;
        for (const double l : logFirst) squares += (l - mean) * (l - mean) / 31;
        const double spread = std::sqrt(squares), expectedSpread = M_PI / (m * std::sqrt(6.0));
        std::printf("glass bar, h = %.3f m, %.4f m^2 of bonds: first crack at a median %.1f MPa (weakest link %.1f MPa, %+.1f %%), spread of ln "
                    "%.3f (Weibull %.3f, %+.0f %%); the bar's peak %.3f times its first crack\n",
                    h, areaM2, median / 1e6, medianPa / 1e6, 100 * (median / medianPa - 1), spread, expectedSpread, 100 * (spread / expectedSpread - 1),
                    peakOverFirst);
        EXPECT_NEAR(median, medianPa, 0.10 * medianPa) << "h = " << h;
        EXPECT_NEAR(spread, expectedSpread, 0.35 * expectedSpread) << "h = " << h;
        EXPECT_LT(peakOverFirst, 1.25) << "h = " << h;
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
    Material glass = withoutStrengthScatter(findMaterialPreset("glass"));
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

TEST(Lattice, DavisonStevensHeldAtAStretchDamagesAsItsClosedFormSays)
{
    // One bond, both its particles held, stretched at once to e = 1.08 times its peak stretch
    // and held there (a longer bar would localise: its softening is unstable). The softening line allows (1 − d) e of ft there, d its
    // damage at e; the bond carries (1 − D) e, so the excess is e (d − D) and with u = d − D,
    // du/dt = −B [exp(a u) − 1], a = (C ft) e. Separating variables,
    // u(t) = −ln(1 − (1 − exp(−a d)) exp(−a B t)) / a: the damage must follow it.
    Material material = kConcrete;
    material.strengthRateLaw = StrengthRateLaw::FibModelCode2010;
    const int nx = 2;
    Body body = test::boxBody(nx, 1, 1, kH, material.densityKgM3);
    for (auto it = body.grid->tree().beginValueOn(); it; ++it)
        if (it.getCoord().x() == 0 || it.getCoord().x() == nx - 1) it.setValue(*it | kAnchorBit);
    LatticeSettings settings;
    settings.damageLaw = LatticeDamageLaw::DavisonStevens;
    Lattice lattice = Lattice::fromBody(body, material, StaticWorld(), settings);
    const LatticeStiffness::Strength& strength = lattice.model().stiffness.strength[0];
    const double e = 1.08, u0 = strength.peakStretchM, uf = strength.zeroTractionStretchM;
    const double lineDamage = 1.0 - (1.0 / e) * (uf - e * u0) / (uf - u0);
    const double x0 = lattice.state.positionM[0].x();
    for (Eigen::Vector3d& x : lattice.state.positionM) x.x() = x0 + (x.x() - x0) * (1.0 + e * u0 / kH);
    const DavisonStevensConstants& law = lattice.model().stiffness.davisonStevens;
    const double a = law.excessExponent * e, rateB = law.rateTimesPeakStrainPerS / (u0 / kH);
    auto closedForm = [&](double t) { return lineDamage + std::log1p(-(-std::expm1(-a * lineDamage)) * std::exp(-a * rateB * t)) / a; };
    const double dt = lattice.stableTimeStepS();
    double t = 0.0, worst = 0.0;
    for (const double checkS : {0.1 / (a * rateB), 0.5 / (a * rateB), 2.0 / (a * rateB)}) {
        for (; t < checkS; t += dt) lattice.step(dt);
        double damage = 0.0;
        for (size_t b = 0; b < lattice.bondCount(); ++b) damage = std::max(damage, lattice.bondDamage(b));
        std::printf("held at %.2f x its peak stretch (line's damage %.4f): after %.3f s damage %.6f, closed form %.6f\n", e, lineDamage, t,
                    damage, closedForm(t));
        worst = std::max(worst, std::abs(damage - closedForm(t)) / closedForm(t));
    }
    // Explicit steps of a microsecond on a time scale of 1 / (a B), a fraction of a second.
    EXPECT_LT(worst, 1e-3);
}

TEST(Lattice, DavisonStevensPeaksAsTheModelCodeSaysBetweenItsFitRatesAndKeepsTheCrackBandsEnergy)
{
    // Davison–Stevens fitted to fib MC2010's tension law at 1e-3 and 10 1/s (RateDamage.h), in
    // a lattice bar pulled at rates it was not fitted at: 0.5 mm/s and 5 cm/s over its 4 cm
    // (0.0125 and 1.25 1/s), where MC2010 gives 1.185 and 1.288. The peak must be within 10 %
    // of those (the grips' concentration, the bar's inertia and the softening line falling
    // under the overstress are the differences). The crack's energy per area must not depend on
    // the voxel size: within 10 % of each other at h and h/2, as with the strength law
    // (RateLawRaisesTheStrengthButNotTheFractureEnergyAtAnyVoxelSize).
    Material material = kConcrete;
    material.strengthRateLaw = StrengthRateLaw::FibModelCode2010;
    const double expectedJ = material.fractureEnergyJPerM2 * 0.02 * 0.02;
    const std::pair<double, double> pullAndFactor[] = {{5e-4, 1.185}, {0.05, 1.288}};
    for (const auto& [pullMS, factor] : pullAndFactor) {
        std::vector<double> perGf;
        for (const int perCm : {1, 2}) {
            BarSpec spec;
            spec.material = material;
            spec.law = LatticeDamageLaw::DavisonStevens;
            spec.h = 0.01 / perCm;
            spec.pullMS = pullMS;
            const BarPull pull = pullBarApart(spec);
            spec.law = LatticeDamageLaw::Softening;
            spec.material.strengthRateLaw = StrengthRateLaw::None;
            const double rateFreePeakPa = pullBarApart(spec).peakStressPa;
            perGf.push_back(pull.dissipatedJ / expectedJ);
            std::printf("Davison-Stevens, %.4f m/s, h = %.4f m: dissipated %.3f x Gf x area; peak %.3f x the rate-free bar's (MC2010 %.3f); %d of %d "
                        "bonds across broken\n",
                        pullMS, spec.h, perGf.back(), pull.peakStressPa / rateFreePeakPa, factor, pull.broken, pull.across);
            EXPECT_EQ(pull.broken, pull.across) << pullMS << " m/s, h = " << spec.h;
            EXPECT_NEAR(pull.peakStressPa / rateFreePeakPa, factor, 0.10 * factor) << pullMS << " m/s, h = " << spec.h;
        }
        EXPECT_NEAR(perGf[1], perGf[0], 0.10 * perGf[0]) << pullMS << " m/s";
    }
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
