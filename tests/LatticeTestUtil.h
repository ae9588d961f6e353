// What the lattice tests share (test_lattice.cpp, test_lattice_fracture.cpp,
// test_lattice_materials.cpp, test_deformable*.cpp): a concrete, boxes of it at 1 cm, and settings that switch off what
// a closed form leaves out.
#pragma once

#include "TestUtil.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>

#include <cmath>
#include <numeric>
#include <vector>

namespace spall::test {

/// A concrete of the fib Model Code 2010's order of magnitude (C30 has E ≈ 33.6 GPa), with the
/// strength and fracture energy the lattice tests were written for.
inline Material latticeConcrete()
{
    Material m;
    m.densityKgM3 = 2400.0;
    m.youngsModulusPa = 30e9;
    m.poissonRatio = 0.2;
    m.tensileStrengthPa = 3e6;
    m.fractureEnergyJPerM2 = 100.0;
    return m;
}
inline const Material kConcrete = latticeConcrete();

/// A material's mean properties: every bond alike (its strength scatter has its own tests).
inline Material withoutStrengthScatter(Material m)
{
    m.strengthDistribution = StrengthDistribution::Lognormal;
    m.strengthCoefficientOfVariation = 0.0;
    m.unitStrengthCoefficientOfVariation = 0.0;
    return m;
}
inline constexpr double kH = 0.01;  ///< the voxel size of latticeOfBox (unit: m)

inline Lattice latticeOfBox(int nx, int ny, int nz, const Material& material = kConcrete, const LatticeSettings& settings = LatticeSettings())
{
    Body body = test::boxBody(nx, ny, nz, kH, material.densityKgM3);
    return Lattice::fromBody(body, material, StaticWorld(), settings);
}

/// `material` with the damping ratio `zeta`.
inline Material damped(Material material, double zeta)
{
    material.dampingRatio = zeta;
    return material;
}

/// The deformable phase's settings with its bulk viscosity off (its dashpots would take energy,
/// or count as strength).
inline LatticeSettings withoutBulkViscosity()
{
    LatticeSettings settings;
    settings.bulkViscosity = 0.0;
    return settings;
}

inline double barWaveSpeed(const Material& m) { return std::sqrt(m.youngsModulusPa / m.densityKgM3); }

inline std::vector<uint32_t> allParticles(const Lattice& lattice)
{
    std::vector<uint32_t> all(lattice.particleCount());
    std::iota(all.begin(), all.end(), 0u);
    return all;
}

/// Linear and angular momentum (about the origin) of some particles.
inline std::pair<Eigen::Vector3d, Eigen::Vector3d> momentaOf(const Lattice& lattice, const std::vector<uint32_t>& particles)
{
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    for (const uint32_t p : particles) {
        linear += lattice.model().particleMassKg * lattice.state.velocityMS[p];
        angular += lattice.state.positionM[p].cross(lattice.model().particleMassKg * lattice.state.velocityMS[p]) +
                   lattice.model().particleInertiaKgM2 * lattice.state.angularVelocityRadS[p];
    }
    return {linear, angular};
}

}  // namespace spall::test
