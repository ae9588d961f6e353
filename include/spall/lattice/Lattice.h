// The deformable phase's lattice (issue 17): a body's voxels as particles with six degrees of
// freedom, its intact links as elastic bonds, integrated explicitly.
//
// Bonds are beam-like (the parallel bond of Potyondy & Cundall 2004, Int. J. Rock Mech. Min. Sci.
// 41:1329): a normal, a shear, a bending and a twisting stiffness, acting at the face between two
// voxels in a frame that turns with them (half-way between their orientations), so rigid motion
// strains nothing. A nearest-neighbour cubic lattice alone has Poisson's ratio 0; each particle
// therefore also carries the volumetric energy ½ λ h³ (tr ε)², tr ε from its bonds' stretches (a
// central force along each bond, so energy and momentum stay exact), which makes the lattice's linear elasticity exactly isotropic in the bulk (C11 = λ + 2μ,
// C12 = λ, C44 = μ; docs/accuracy.md measures it where surfaces break the bulk).
#pragma once

#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <vector>

namespace spall {

/// The elastic constants a lattice reproduces.
struct ElasticConstants {
    double densityKgM3 = 2400.0;
    double youngsModulusPa = 30e9;
    double poissonRatio = 0.2;
};

/// One bond's stiffnesses and the volumetric modulus, for voxels of edge h. Derivation (energy
/// per voxel of the lattice equal to the continuum's, docs/architecture.md): normal and shear
/// 2μh, so C11 − C12 = 2μ and C44 = μ; bending E h³/12 and twisting 0.1406 G h³, those of a
/// square beam of side and length h (Roark's torsion constant 0.1406 a⁴), which matter only at
/// the scale of a voxel.
struct LatticeStiffness {
    double normalNPerM = 0.0;
    double shearNPerM = 0.0;
    double bendingNmPerRad = 0.0;
    double twistingNmPerRad = 0.0;
    double lameLambdaPa = 0.0;
    double shearModulusPa = 0.0;
};
LatticeStiffness calibrateLattice(const ElasticConstants& material, double voxelSizeM);

/// A bond joins particle `low` to its +axis neighbour `high`.
struct LatticeBond {
    uint32_t low = 0, high = 0;
    int axis = 0;
};

/// A bond's deformation, in its frame (half-way between its particles' orientations).
struct BondStrain {
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  ///< bond frame to world
    Eigen::Vector3d displacementM = Eigen::Vector3d::Zero();  ///< of high relative to low, less the rest length
    Eigen::Vector3d rotationRad = Eigen::Vector3d::Zero();    ///< of high relative to low
};

/// Particles (one per voxel, in the grid's leaf order) and bonds (one per intact link) as flat
/// arrays. The caller sets externalForceN before a step (it acts through the step); step()
/// integrates by velocity Verlet, symplectic, so with no damping the energy oscillates but does
/// not drift. Held particles (the body's anchored voxels) stay where they are.
class Lattice {
public:
    /// A body's voxels at their world places, moving with the body's rigid velocity field.
    static Lattice fromBody(const Body& body, const ElasticConstants& material);

    size_t particleCount() const { return positionM.size(); }
    size_t bondCount() const { return bonds.size(); }

    /// Largest stable step (unit: s): 0.9 × 2/ω with ω bounding the lattice's highest frequency,
    /// the rotational optical mode of the shear bonds (ω² = 24 μ h / m) and the translational
    /// breathing mode (ω² = (8μ + 12λ) h / m) added.
    double stableTimeStepS() const;
    void step(double dtS);

    double kineticEnergyJ() const;
    /// Of the strains as the last step (or construction) left them.
    double strainEnergyJ() const;
    Eigen::Vector3d linearMomentum() const;
    Eigen::Vector3d angularMomentumAboutOrigin() const;

    // State, world frame, one entry per particle.
    std::vector<openvdb::Coord> voxel;  ///< the body's index of each particle
    std::vector<Eigen::Vector3d> positionM, velocityMS, angularVelocityRadS, externalForceN;
    std::vector<Eigen::Quaterniond> orientation;
    std::vector<uint8_t> held;  ///< 1: fixed to the world (an anchored voxel)
    std::vector<LatticeBond> bonds;

    double voxelSizeM = 0.0;
    double particleMassKg = 0.0;
    double particleInertiaKgM2 = 0.0;  ///< a cube's, m h² / 6, the same about every axis
    LatticeStiffness stiffness;

private:
    /// Per particle, the particle across each face (LinkBits.h's Face order) or -1.
    std::vector<std::array<int32_t, 6>> mNeighbour;
    /// Per particle, λ for the axes it has bonds along (stress-free missing axes condensed out).
    std::vector<double> mLambdaPa;
    /// Bonds in six batches, by axis and by the parity of the low particle's index along it: no
    /// two bonds of a batch share a particle, so a batch adds its forces in parallel without
    /// races, and each particle's sum has the same order whatever the thread count.
    std::array<std::vector<uint32_t>, 6> mBatches;
    /// Per particle and axis, 1 / (its bonds along the axis), or 0 without any.
    std::vector<Eigen::Vector3d> mInverseBondCount;
    // Per particle: tr ε, λ tr ε / (bonds along each axis), and the bonds' force and moment on it
    // (external forces apart).
    std::vector<double> mVolumetricStrain;
    std::vector<Eigen::Vector3d> mVolumetricStressShare;
    std::vector<Eigen::Vector3d> mForceN, mMomentNm;

    /// Each particle's tr ε: per axis, the mean stretch (length change / h) of its bonds along it.
    void computeVolumetricStrain();
    void computeForces();
    /// f(i) for i < count: in parallel for large lattices, in order for small ones.
    template <typename F>
    void forEach(size_t count, const F& f) const;
    void addBondForces(const LatticeBond& bond);
    BondStrain strainOf(const LatticeBond& bond) const;

};

}  // namespace spall
