// A bar of a material loaded along x between held grips, pulled apart or squeezed until it
// breaks or crushes through (test_lattice_fracture.cpp, test_lattice_crushing.cpp): the energy
// balance, the peak stress and which bonds failed.
#pragma once

#include "LatticeTestUtil.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>

#include <algorithm>
#include <cmath>

namespace spall::test {

struct BarPull {
    double dissipatedJ = 0.0, peakStressPa = 0.0, youngsModulusPa = 0.0;
    int broken = 0, across = 0, damagedElsewhere = 0;
    int brokenAnywhere = 0;  ///< bonds along any axis, anywhere
    int crushedAcross = 0;   ///< bonds across the middle crushed through
    bool fellPastPeak = false;  ///< the stress fell to half its peak
    double firstDamageStressPa = 0.0;  ///< the stress when a bond first took damage (BarSpec::watchFirstDamage)
};

/// A bar loaded in direct tension (pullMS > 0) or compression (pullMS < 0): `material`, length ×
/// side × side, voxel size h, one end moved at pullMS, the bonds across its middle `notch` times
/// as strong as the rest.
struct BarSpec {
    Material material = kConcrete;
    double lengthM = 0.04, sideM = 0.02, h = 0.01, pullMS = 0.05, notch = 0.8;
    LatticeDamageLaw law = LatticeDamageLaw::Softening;
    double bulkViscosity = LatticeSettings().bulkViscosity;
    uint64_t seed = 1;  ///< draws the material's strength scatter, if it has one
    bool watchFirstDamage = false;  ///< look for the first damaged bond every step (BarPull::firstDamageStressPa)
};

/// What a bar of the material loaded along x should show: along the grain when it lies along x.
struct TensionTarget {
    double youngsModulusPa, tensileStrengthPa, fractureEnergyJPerM2;
    int strengthClass;
};
inline TensionTarget tensionTargetOf(const Material& m)
{
    if (m.grainAxis == GrainAxis::X) return {m.alongGrainYoungsModulusPa, m.alongGrainTensileStrengthPa, m.alongGrainFractureEnergyJPerM2, 1};
    return {m.youngsModulusPa, m.tensileStrengthPa, m.fractureEnergyJPerM2, 0};
}

/// The bar's end layers held (the grips), one end moved (the whole bar starting on the matching
/// uniform strain rate, so no shock runs ahead) for loadTimeS. Held layers cannot contract or
/// spread sideways, which concentrates stress at the grips' corners (more sharply the finer h):
/// the quarters next to the grips are 50 % stronger, as a dog-bone specimen's are thicker; the
/// bonds across the middle are `notch` times as strong (each as drawn, for a material that scatters). Energy balance: work done on the held
/// ends minus what is left as kinetic and strain energy is what the cracks and crushing took. E
/// is the stress over the mean strain between the grips when the stress first reaches
/// `modulusAtPa`. The stress is positive in the load's sense (tension pulled, compression
/// squeezed); its peak is the highest before it first falls to half of it.
inline BarPull loadBar(const BarSpec& spec, double loadTimeS, double modulusAtPa)
{
    const Material& material = spec.material;
    const double h = spec.h, pullMS = spec.pullMS, sideM = spec.sideM;
    const int nx = int(std::lround(spec.lengthM / h)), ny = int(std::lround(sideM / h));
    Body body = test::boxBody(nx, ny, ny, h, material.densityKgM3);
    for (auto it = body.grid->tree().beginValueOn(); it; ++it)
        if (it.getCoord().x() == 0 || it.getCoord().x() == nx - 1) it.setValue(*it | kAnchorBit);
    LatticeSettings settings;
    settings.damageLaw = spec.law;
    settings.bulkViscosity = spec.bulkViscosity;
    Lattice lattice = Lattice::fromBody(body, material, StaticWorld(), settings, VoxelBlocks(), spec.seed);
    const double x0 = lattice.state.positionM[0].x(), gaugeM = (nx - 1) * h;
    for (size_t p = 0; p < lattice.particleCount(); ++p) {
        lattice.state.velocityMS[p] = Eigen::Vector3d(pullMS * (lattice.state.positionM[p].x() - x0) / gaugeM, 0, 0);
        if (lattice.model().held[p] && lattice.model().voxel[p].x() == 0) lattice.state.velocityMS[p].setZero();
    }
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        const int x = lattice.model().voxel[lattice.model().bonds[b].low].x();
        if (x < nx / 4 || x >= nx - nx / 4) lattice.state.bondHistory[b].strengthScale *= 1.5;
        if (lattice.model().bonds[b].axis == 0 && x == nx / 2 - 1) lattice.state.bondHistory[b].strengthScale *= spec.notch;
    }
    const double energy0 = lattice.kineticEnergyJ() + lattice.strainEnergyJ();
    const double dt = lattice.stableTimeStepS(), speedMS = std::abs(pullMS);
    BarPull result;
    double workJ = 0.0;
    auto heldPower = [&] {  // the agent holding the ends balances the bonds' force on them
        double power = 0.0;
        for (size_t p = 0; p < lattice.particleCount(); ++p)
            if (lattice.model().held[p]) power -= lattice.state.bondForceN[p].dot(lattice.state.velocityMS[p]);
        return power;
    };
    const auto anyDamaged = [&] {
        for (size_t b = 0; b < lattice.bondCount(); ++b)
            if (lattice.bondDamage(b) > 0.0) return true;
        return false;
    };
    double lastStressPa = 0.0;
    for (double t = 0.0; t < loadTimeS; t += dt) {
        const double before = heldPower();
        lattice.step(dt);
        if (spec.watchFirstDamage && result.firstDamageStressPa == 0.0 && anyDamaged()) result.firstDamageStressPa = lastStressPa;
        workJ += 0.5 * (before + heldPower()) * dt;
        const double stressPa = heldPower() / speedMS / (sideM * sideM);
        if (result.youngsModulusPa == 0.0 && stressPa >= modulusAtPa) result.youngsModulusPa = stressPa / (speedMS * (t + dt) / gaugeM);
        // The failure's peak: a crushed band's rubble carries again once squeezed through.
        if (stressPa < 0.5 * result.peakStressPa) result.fellPastPeak = true;
        if (!result.fellPastPeak) result.peakStressPa = std::max(result.peakStressPa, stressPa);
        lastStressPa = stressPa;
    }
    result.dissipatedJ = workJ - (lattice.kineticEnergyJ() + lattice.strainEnergyJ() - energy0);
    for (size_t b = 0; b < lattice.bondCount(); ++b) {
        result.brokenAnywhere += lattice.bondDamage(b) == 1.0;
        if (lattice.model().bonds[b].axis != 0) continue;
        const bool middle = lattice.model().voxel[lattice.model().bonds[b].low].x() == nx / 2 - 1;
        result.across += middle;
        result.broken += middle && lattice.bondDamage(b) == 1.0;
        result.crushedAcross += middle && lattice.crushingDamage(b) == 1.0;
        result.damagedElsewhere += !middle && lattice.bondDamage(b) > 0.5;
    }
    return result;
}

/// Pulled long enough to stretch the bar to its strength and open the crack through; E measured
/// at ft / 2.
inline BarPull pullBarApart(const BarSpec& spec)
{
    const TensionTarget target = tensionTargetOf(spec.material);
    const double gaugeM = (std::lround(spec.lengthM / spec.h) - 1) * spec.h;
    const LatticeStiffness stiffness = calibrateLattice(spec.material, spec.h);
    const double pullTimeS =
        1.5 * (stiffness.strength[target.strengthClass].zeroTractionStretchM + target.tensileStrengthPa / target.youngsModulusPa * gaugeM) / spec.pullMS;
    return loadBar(spec, pullTimeS, 0.5 * target.tensileStrengthPa);
}

}  // namespace spall::test
