// What a lattice is made of (lattice/Lattice.h): the bonds' stiffness and strength calibrated
// from the material, what each bond remembers, a lattice's state (what a step carries to the next
// and a checkpoint saves) and its model (what it is built with and keeps unchanged).
#pragma once

#include <spall/fracture/Material.h>
#include <spall/lattice/ParticleBlocks.h>
#include <spall/lattice/RateDamage.h>
#include <spall/lattice/Settings.h>
#include <spall/world/StaticWorld.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace spall {

/// The bonds' stiffnesses per axis of the body's index space and the volumetric modulus, for
/// voxels of edge h. Derivation (energy per voxel of the lattice equal to the continuum's,
/// docs/architecture.md): the normal stiffness matrix is diag(d) + λ 1 1ᵀ, normal bonds d h;
/// a bond along a displaced across it along b shears the plane (a, b), and its spring there is
/// 2 h G of that plane, as is the spring of the plane's other bond, so C44 of each plane is
/// G_ab whether the particles turn with the material or their rotations relax (a bond with one
/// spring for both its directions puts a plane's two springs in series when they relax, issue
/// 47); bending E h³/12 and twisting 0.1406 G h³, those of a square beam of side and length h
/// (Roark's torsion constant 0.1406 a⁴), which matter only at the scale of a voxel. Isotropic:
/// d = 2μ, s = 2μh. Wood (a grain axis L) is transversely isotropic: d differs along L, and the
/// planes holding L have G_L (docs/accuracy.md).
struct LatticeStiffness {
    std::array<double, 3> normalNPerM{};
    /// Per bond axis a, its shear spring along each direction b ≠ a (component a is 0) (unit: N/m).
    std::array<Eigen::Vector3d, 3> shearNPerM{};
    std::array<double, 3> bendingNmPerRad{};
    std::array<double, 3> twistingNmPerRad{};
    /// d per axis, the normal stiffness less λ (2μ when isotropic) (unit: Pa).
    std::array<double, 3> normalModulusPa{};
    double lameLambdaPa = 0.0;
    /// What a bond fails at; a material built of units (masonry) or with a grain (wood) has
    /// two: [0] the material's own, which for masonry is its joints' and for wood across the
    /// grain, and [1] inside a unit (across the courses when particles are taller than a
    /// course: acrossCoursesStrengthRatio), or along the grain.
    struct Strength {
        /// E along the bond, which turns its stretch into stress in uniaxial tension (unit: Pa).
        double youngsModulusPa = 0.0;
        /// Linear softening in tension, crack band style (Bažant & Oh 1983): a bond's normal
        /// stretch peaks at u0 = ft h / E and its traction falls to nothing at uf = 2 Gf / ft,
        /// so a broken bond has dissipated Gf per unit of its face, whatever h. That needs
        /// uf > u0, h < 2 E Gf / ft² (0.55 mm for glass, 1.1 m for brick masonry); above it
        /// uf = u0: brittle at the full strength, giving what it held beyond Gf back to its
        /// particles (Lattice::releaseSnapEnergies).
        double peakStretchM = 0.0;
        double zeroTractionStretchM = 0.0;
        /// Gf, beyond which a bond too large to soften gives its elastic energy back when it
        /// snaps (Lattice::releaseSnapEnergies) (unit: J/m²).
        double fractureEnergyJPerM2 = 0.0;
        /// Mohr–Coulomb with the tension cut-off (Material): the shear strength at no normal
        /// stress and the friction coefficient, the friction on the bond's normal traction.
        /// (The cut-off is on the normal strain, E ε = ft, exact in uniaxial stress and 11 %
        /// stronger than a stress cut-off in uniaxial strain at ν = 0.2.)
        double shearStrengthPa = 0.0;
        double frictionCoefficient = 0.0;
        /// Crushing (Lattice::crushingShorteningM), 0: never. A bond's compression, as its
        /// undamaged material would carry it, against the strength at the confinement across it,
        /// Hoek–Brown's σ1 = σ3 + fc √(m σ3 / fc + 1) with m = fc / ft (Hoek & Brown 1997, Int.
        /// J. Rock Mech. Min. Sci. 34(8); m ≈ fc / ft puts its uniaxial tension near ft): fc in
        /// uniaxial compression, about 6 fc in uniaxial strain (a plane wave), never under
        /// hydrostatic pressure. It softens linearly over its shortening, peaking at fc h / E and
        /// carrying nothing at 2 Gc / fc, so a crushed band takes Gc per area at any h (the crack
        /// band in compression) (unit: Pa, 1, m, m).
        double compressiveStrengthPa = 0.0;
        double confinementM = 0.0;
        double crushingPeakShorteningM = 0.0;
        double crushingEndShorteningM = 0.0;
    };
    std::array<Strength, 2> strength;
    StrengthRateLaw strengthRateLaw = StrengthRateLaw::None;
    /// Davison–Stevens (that damage law only), fitted to the material's strain-rate law, which
    /// the law then replaces: strengthRateLaw is None.
    DavisonStevensConstants davisonStevens;
};
/// From the material's density, E, ν, tensile strength and Gf (fracture/Material.h), and for
/// wood its values along the grain.
LatticeStiffness calibrateLattice(const Material& material, double voxelSizeM);
/// A particle's λ condensed over the axes it has no bond along (σ = 0 there): λ / (1 + λ Σ_missing
/// 1/d); isotropic, λ for three axes, 2μλ / (λ + 2μ) for two (plane stress), λμ / (λ + μ) for
/// one (a bar: E = 2μ + that) (unit: Pa).
double condensedLambdaPa(const LatticeStiffness& stiffness, const std::array<bool, 3>& bondedAlong);
/// The highest angular frequency of a lattice of these springs and particles (cubes of edge
/// `spacingM`): the largest of its Bloch waves' in the bulk and along faces and edges (slabs and
/// bars up to three particles across) and of small cubes' modes (LatticeFrequency.cpp) (unit: rad/s).
double highestFrequencyRadS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg);
/// The step velocity Verlet takes on such a lattice, each bond with a dashpot along it: 0.9 ×
/// 2 / highestFrequencyRadS, a tenth inside its limit, or shorter where the dashpots limit it
/// (Lattice::stableTimeStepS; known before a lattice is built, for the run's cost estimate)
/// (unit: s).
double stableTimeStepS(const LatticeStiffness& stiffness, double spacingM, double particleMassKg, double bondDashpotNSPerM = 0.0);

/// What a bond remembers (all of it saved with a checkpoint).
struct BondHistory {
    /// Its strength as a fraction of the material's (1 by default; a notch, a weak joint).
    double strengthScale = 1.0;
    /// The largest equivalent stretch it has seen (Lattice::equivalentStretchM): what drives its
    /// damage along the softening line (unit: m).
    double maxEquivalentStretchM = 0.0;
    /// The material's strain-rate law raises a bond's strength, not its fracture energy: its
    /// softening line starts at strengthFactor × its peak stretch and ends where the area under
    /// it is still Gf (Lattice::softeningDamage). The factor is the dynamic increase factor
    /// averaged over the bond's loading up to its peak, weighted by each increase of its stretch
    /// (ringing swings the instantaneous rate through zero; a bond loaded steadily at a rate is
    /// as strong as the law says), and frozen once the bond is damaged: after that its opening
    /// rate is a crack's, which grows as 1/h, and the line stays where the continuum's rate put
    /// it (unit: 1).
    double strengthFactor = 1.0;
    /// The same stretch with each increase divided by the factor at the strain rate of that
    /// moment, while the bond is undamaged (rate laws only): strengthFactor is the stretch over
    /// it (unit: m).
    double rateWeightedStretchM = 0.0;
    /// Davison–Stevens damage (that law only) (unit: 1).
    double rateDamage = 0.0;
    /// The largest equivalent shortening in compression (Lattice::crushingShorteningM): what
    /// drives its crushing along the compressive softening line (unit: m).
    double maxCrushingShorteningM = 0.0;
};

/// The most damage a bond still intact can carry into a body's link damage and back (Vec4s
/// storage is single precision; 1 would be broken).
inline constexpr double kLargestIntactDamage = 0.99999;

/// A bond joins particle `low` to its +axis neighbour `high`.
struct LatticeBond {
    uint32_t low = 0, high = 0;
    int axis = 0;
    /// Which of LatticeStiffness::strength it fails at: 1 inside a masonry unit or along wood's
    /// grain, else 0.
    uint8_t strengthClass = 0;
    /// A support bond of a box that holds by a pin (StaticWorld::pinned): only its shear
    /// spring, at its voxel's centre, so the voxel turns freely on it and slides along its axis
    /// (a pane's edge in its glazing's clearance); it fails in shear. However many voxels thick
    /// the body, its edge is then a hinge.
    uint8_t pinned = 0;
};

/// A bond's deformation, in its frame (half-way between its particles' orientations).
struct BondStrain {
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  ///< bond frame to world
    Eigen::Vector3d displacementM = Eigen::Vector3d::Zero();  ///< of high relative to low, less the rest length
    Eigen::Vector3d rotationRad = Eigen::Vector3d::Zero();    ///< of high relative to low
};

/// What a lattice carries from one step to the next, and all that a checkpoint saves of it:
/// per particle (world frame) its motion and the forces velocity Verlet carries, per bond its
/// history. The rest follows from its body (Lattice::fromBody) or is a step's scratch.
struct LatticeState {
    std::vector<Eigen::Vector3d> positionM, velocityMS, angularVelocityRadS;
    std::vector<Eigen::Quaterniond> orientation;
    /// The bonds' force and moment on each particle, with the contacts' between particles that
    /// share no bond, as the last step left them (unit: N, N m): velocity Verlet's first half
    /// kick of the next step uses them. They depend on the velocities half-way through that step
    /// (the dashpots), so a checkpoint saves them.
    std::vector<Eigen::Vector3d> bondForceN, bondMomentNm;
    std::vector<BondHistory> bondHistory;
};

/// What a lattice is built with and keeps unchanged (Lattice::fromBody): its particles, its bonds
/// with their stiffness and strength, its settings, and what holds it and what it may not pass
/// through. Copies of a lattice share its particle index.
struct LatticeModel {
    // Particles.
    /// Particles [0, voxelParticleCount) are the body's voxels, in its leaf order; those after
    /// them are its anchors' support points (held).
    size_t voxelParticleCount = 0;
    std::vector<openvdb::Coord> voxel;  ///< the body's index of each particle (a support point: the cell beyond its voxel)
    std::vector<uint8_t> held;          ///< 1: fixed to the world (an anchored voxel)
    /// The distance between neighbouring particles, each a cube of this edge: the voxel size of
    /// the body it was built from, k h for blocks of k voxels (`blocks`) (unit: m).
    double spacingM = 0.0;
    /// How the body's voxels make the particles (a particle per voxel by default): `voxel`
    /// holds the blocks' cells.
    VoxelBlocks blocks;
    double particleMassKg = 0.0;
    double particleInertiaKgM2 = 0.0;  ///< a cube's, m h² / 6, the same about every axis
    /// stableTimeStepS of its stiffness and particles, found once as it is built (unit: s).
    double stableStepS = 0.0;
    /// The body's orientation when the lattice was built: a particle's rest place in the world
    /// is its index × spacing turned by it (about the body's place). A held piece's rotation away
    /// from rest is measured against it (Lattice::openSupportHinges).
    Eigen::Quaterniond restOrientation = Eigen::Quaterniond::Identity();

    // Bonds.
    std::vector<LatticeBond> bonds;
    /// Particle numbers by voxel, in a tree of the body's own shape (and its ground points).
    std::shared_ptr<LinkTree> particleIndex = std::make_shared<LinkTree>(-1);
    /// Per particle, the bond across each face (LinkBits.h's Face order) or -1.
    std::vector<std::array<int32_t, 6>> bondAcross;
    /// Per voxel particle, its bond to a ground point, or -1.
    std::vector<int32_t> groundBond;
    /// The bonds with a held end (a support point, or an anchored voxel held itself), in bond
    /// order: what Lattice::heldBySupport looks at, every step of an anchored body.
    std::vector<uint32_t> bondsToHeld;

    // The material's response.
    LatticeStiffness stiffness;
    /// Per particle, λ for the axes it has bonds along (stress-free missing axes condensed out).
    std::vector<double> lambdaPa;
    /// Per particle and axis, 1 / (its bonds along the axis), or 0 without any.
    std::vector<Eigen::Vector3d> inverseBondCount;
    double dashpotPerViscosityNSPerM = 0.0;  ///< ρ c h² (unit: N s/m)
    /// The failure index's factors for a strength class and axis, found once when the lattice
    /// is built, not once a bond.
    struct FailureTerms {
        double peakStretchM = 0.0;        ///< u0
        double tensionIndexPerM = 0.0;    ///< 1 / u0
        Eigen::Vector3d shearIndexPerM = Eigen::Vector3d::Zero();  ///< k_s / (h² c) per direction: shear displacement to index
        double normalIndexPerM = 0.0;     ///< k_n / (h² c): normal displacement to traction over c
        double indexPerPa = 0.0;          ///< 1 / c
        double frictionCoefficient = 0.0;
    };
    std::array<std::array<FailureTerms, 3>, 2> failureTerms{};
    /// Linear bulk viscosity: a dashpot along each bond of ζ ρ c h² (c the P-wave speed), as
    /// explicit codes damp the ringing of a discretised shock front (von Neumann & Richtmyer 1950;
    /// LS-DYNA's linear term Q2, 0.06 by default there), softening with the bond as it opens (a
    /// crack carries no viscous stress). Without it a sharp front rings and a
    /// free face's reflection puts spurious tension a few voxels deep (docs/accuracy.md). 0 turns
    /// it off (LatticeSettings::bulkViscosity).
    double bulkViscosity = 0.0;
    /// The material's damping ratio (Material::dampingRatio): after each step every piece's
    /// velocities about its rigid motion decay as mass-proportional damping of that ratio at the
    /// piece's fundamental frequency would make them (dampVibration). 0 turns it off.
    double dampingRatio = 0.0;
    LatticeDamageLaw damageLaw = LatticeDamageLaw::Softening;  ///< LatticeSettings::damageLaw
    double handOffResidualStrength = 0.0;  ///< LatticeSettings::handoffResidualStrength

    // What holds it and what it may not pass through.
    /// A surface a particle presses on elastically (the ground, a collider's face): a normal
    /// spring as stiff as a bond (less on a compliant ground), a dashpot that damps a particle's
    /// bounce to the surface's restitution, the waves a compliant ground carries away, and
    /// Coulomb's friction (Lattice::pressOn).
    struct SurfaceContact {
        double stiffnessNPerM = 0.0;
        double dashpotNSPerM = 0.0;    ///< while the particle leaves
        double radiationNSPerM = 0.0;  ///< both ways: the ground's impedance (GroundCompliance)
        double friction = 0.0;         ///< Coulomb coefficient (unit: 1)
    };
    /// The ground plane n·x = offset its particles' cubes press on; its offset lowered to where
    /// the lattice's lowest cubes rest.
    GroundPlane ground = GroundPlane{false};
    /// The boxes of keepOutOf, each in its own frame grown by the allowed depth, with the
    /// world-axis bounds of that grown box: a particle outside them costs six comparisons.
    struct KeptOut {
        Eigen::Matrix3d toBox;
        Eigen::Vector3d centreM, reachM;
        Eigen::AlignedBox3d boundsM;
        SurfaceContact contact;
    };
    std::vector<KeptOut> keptOut;
    /// Per particle, how far its cube sank into a collider beyond the allowed depth when it
    /// entered (a voxel's staircase reaches into a slanted or misaligned box): the box pushes
    /// only beyond it, so entering throws nothing out (empty without colliders) (unit: m).
    std::vector<float> colliderSlackM;
    /// A support's dead load on a voxel it holds (StaticBox::bearingPressurePa over the
    /// particle's face), acting while the voxel touches the support (setExternalForces).
    struct BearingLoad {
        uint32_t bond = 0;                                 ///< the support bond
        Eigen::Vector3d forceN = Eigen::Vector3d::Zero();  ///< on its voxel particle, world frame
        double friction = 0.0;  ///< the box's Coulomb coefficient, once the bond has broken (unit: 1)
        /// The voxel particle it bears on (the support point is the bond's other, later, end).
        uint32_t voxel(const std::vector<LatticeBond>& bonds) const { return std::min(bonds[bond].low, bonds[bond].high); }
    };
    std::vector<BearingLoad> bearingLoads;
    /// Per particle, its share of the strain energy its dead loads held when it entered
    /// (settleUnderDeadLoads: half of each of its bonds' and its volumetric term's); empty
    /// without dead loads. A held piece vibrates by what it holds beyond them (unit: J).
    std::vector<float> settledStrainJ;
};

}  // namespace spall
