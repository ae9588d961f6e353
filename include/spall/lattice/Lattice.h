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

#include <spall/core/DisjointSets.h>
#include <spall/fracture/Material.h>
#include <spall/lattice/ParticleBlocks.h>
#include <spall/lattice/Settings.h>
#include <spall/loads/Exposure.h>
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
    /// grain, and [1] inside a unit, or along the grain.
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
    };
    std::array<Strength, 2> strength;
    StrengthRateLaw strengthRateLaw = StrengthRateLaw::None;
    /// Davison–Stevens B (unit: 1/s) and C (unit: 1/Pa; the material's 0 becomes 1/ft).
    double damageRatePerS = 0.0;
    double damageStressScalePerPa = 0.0;
};
/// From the material's density, E, ν, tensile strength and Gf (fracture/Material.h), and for
/// wood its values along the grain.
LatticeStiffness calibrateLattice(const Material& material, double voxelSizeM);

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

    // Bonds.
    std::vector<LatticeBond> bonds;
    /// Particle numbers by voxel, in a tree of the body's own shape (and its ground points).
    std::shared_ptr<LinkTree> particleIndex = std::make_shared<LinkTree>(-1);
    /// Per particle, the bond across each face (LinkBits.h's Face order) or -1.
    std::vector<std::array<int32_t, 6>> bondAcross;
    /// Per voxel particle, its bond to a ground point, or -1.
    std::vector<int32_t> groundBond;

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

    // What holds it and what it may not pass through.
    /// The ground plane n·x = offset its particles' cubes may not sink into: a particle that
    /// would is put back on it and loses its velocity into it (a perfectly plastic contact, as a
    /// rigid body's resting contact; no friction); its offset lowered to where the lattice's
    /// lowest cubes rest.
    GroundPlane ground = GroundPlane{false};
    /// The boxes of keepOutOf, each in its own frame grown by the allowed depth, with the
    /// world-axis bounds of that grown box: a particle outside them costs six comparisons.
    struct KeptOut {
        Eigen::Matrix3d toBox;
        Eigen::Vector3d centreM, reachM;
        Eigen::AlignedBox3d boundsM;
        double friction = 0.0;  ///< Coulomb coefficient along its faces (unit: 1)
    };
    std::vector<KeptOut> keptOut;
    /// A support's dead load on a voxel it holds (StaticBox::bearingPressurePa over the
    /// particle's face), acting while the voxel touches the support (setExternalForces).
    struct BearingLoad {
        uint32_t bond = 0;                                 ///< the support bond
        Eigen::Vector3d forceN = Eigen::Vector3d::Zero();  ///< on its voxel particle, world frame
    };
    std::vector<BearingLoad> bearingLoads;
    /// Per particle, its share of the strain energy its dead loads held when it entered
    /// (settleUnderDeadLoads: half of each of its bonds' and its volumetric term's); empty
    /// without dead loads. A held piece vibrates by what it holds beyond them (unit: J).
    std::vector<float> settledStrainJ;
};

/// Particles (one per voxel, in the grid's leaf order) and bonds (one per intact link) as flat
/// arrays. The caller sets externalForceN before a step (it acts through the step); step()
/// integrates by velocity Verlet, symplectic, so with no damping the energy oscillates but does
/// not drift. Held particles (the body's anchored voxels) stay where they are.
class Lattice {
public:
    /// A body's voxels at their world places, moving with the body's rigid velocity field. Each
    /// anchored voxel is bonded to a held support point a voxel beyond it, by a bond like the
    /// others, so a body can break where it is held: on the ground (within a quarter voxel of
    /// it), across the face that looks most directly into the ground; else across its free face
    /// whose neighbouring cell lies deepest inside a support box. An anchored voxel next to
    /// neither is held.
    /// Its settings are taken here, once: the bulk viscosity and the damage law from `settings`,
    /// the damping ratio from the material, and the scene's `seed`, which draws the strength
    /// scatter (Material::strengthCoefficientOfVariation); with `blocks` of more than one voxel, a
    /// particle per block (ParticleBlocks.h).
    static Lattice fromBody(const Body& body, const Material& material, const StaticWorld& supports = StaticWorld(),
                            const LatticeSettings& settings = LatticeSettings(), const VoxelBlocks& blocks = VoxelBlocks(), uint64_t seed = 1);

    size_t particleCount() const { return state.positionM.size(); }
    /// The particle at a voxel (a support point at the cell beyond its voxel), or -1.
    int32_t particleAt(const openvdb::Coord& ijk) const { return mModel.particleIndex->getValue(ijk); }
    /// The bond across a face of particle p (LinkBits.h's Face order), or -1.
    int32_t bondAcross(size_t p, int face) const { return mModel.bondAcross[p][face]; }
    size_t bondCount() const { return mModel.bonds.size(); }

    /// Largest stable step (unit: s): 0.9 × 2/ω with ω bounding the lattice's highest frequency,
    /// the rotational optical mode of the stiffest shear bonds (ω² = 12 k_s / m; 24 μ h / m
    /// isotropic) and the translational breathing mode (ω² = (4 k_n + 12 λ h) / m, k_n the
    /// stiffest normal bonds; (8μ + 12λ) h / m isotropic) added.
    double stableTimeStepS() const;
    void step(double dtS);
    /// The bonds' forces from the state, leaving their damage as it is (after the state arrays
    /// were written from outside, as a checkpoint does).
    void refreshForces();

    double kineticEnergyJ() const;
    /// Of the strains as the last step (or construction) left them: the bonds' and the
    /// particles' volumetric terms.
    double strainEnergyJ() const;
    double bondStrainEnergyJ(size_t b) const;
    double volumetricEnergyJ(size_t p) const;
    Eigen::Vector3d linearMomentum() const;
    Eigen::Vector3d angularMomentumAboutOrigin() const;

    /// What acts on each particle through the next step besides its bonds (the caller's; unit: N).
    std::vector<Eigen::Vector3d> externalForceN;
    LatticeState state;
    /// How close a bond is to failing, as a stretch: the normal stretch that would load it as
    /// much in pure tension, u0 × f with f its failure index (1 on the failure surface).
    /// Tension: f² = (stretch/u0)² + (τ/c)² (the tension cut-off joined to pure shear by an
    /// ellipse, Camacho & Ortiz 1996's effective traction); compression: f = (|τ| − μ σc)/c,
    /// Mohr–Coulomb. The stretch is the face's most stretched corner's, the bond's bending
    /// included, so a bent member cracks when its surface reaches ft (unit: m).
    double equivalentStretchM(size_t b) const;
    /// 0 intact … 1 broken: the secant stiffness lost in tension, shear and bending (compression
    /// still carries, as contact).
    double bondDamage(size_t b) const;
    /// The particles grouped by the bonds that have not broken.
    DisjointSets intactPieces() const;
    /// A piece's fundamental angular frequency, estimated as an Euler–Bernoulli beam's of
    /// thickness t and length L: free at both ends, ω = 22.37 √(EI / ρAL⁴) = 6.458 c t / L², or
    /// clamped at one, 3.516 √(EI / ρAL⁴) = 1.015 c t / L² (c = √(E / ρ)) (unit: rad/s). A free
    /// piece's t and L are the thinnest and longest sides of its box in the lattice's index
    /// space; a held piece's L is its farthest reach from what holds it (findDampedPieces).
    double fundamentalFrequencyRadS(double thicknessM, double lengthM, bool held) const;

    /// What it was built with (fromBody), unchanged since.
    const LatticeModel& model() const { return mModel; }

private:
    LatticeModel mModel;

    // A step's scratch, found again from the model and the state (never saved).
    // Per particle: tr ε and λ tr ε / (bonds along each axis).
    std::vector<double> mVolumetricStrain;
    std::vector<Eigen::Vector3d> mVolumetricStressShare;
    /// What the force pass takes from each bond, measured once per substep (measureBond).
    struct BondForceTerms {
        Eigen::Vector3d armM;             ///< high − low (unit: m)
        /// On high: the spring and dashpot when measured, the whole force once completed with
        /// the volumetric term (completeBondForce) (unit: N).
        Eigen::Vector3d forceOnHighN;
        Eigen::Vector3d bendingMomentNm;  ///< bending and twisting, on high (unit: N m)
        Eigen::Vector3d pairMomentNm;     ///< of the pair of forces about either centre, −(arm / 2) × force (unit: N m)
        /// Its stretch (length change) as the volumetric term counts it: in tension times
        /// √(1 − D), so the bond's own share of the volumetric force falls with 1 − D as its
        /// spring's does and the traction follows the softening line (unit: m).
        double effectiveStretchM = 0.0;
        /// The volumetric force on high per pascal of its particles' shares, along −arm:
        /// h² √(1 − D in tension) / |arm| (unit: m).
        double volumetricAreaPerArmM = 0.0;
    };
    std::vector<BondForceTerms> mBondTerms;
    // Damping (dampVibration): the pieces as the last bond to break left them, each with the
    // decay rate of its velocities about its rigid motion, 2 ζ ω (Clough & Penzien, Dynamics
    // of Structures, 1993, §12-4: mass-proportional damping a0 M damps mode n at a0 / 2 ω_n).
    struct DampedPiece {
        bool held = false;
        double decayPerS = 0.0;
        uint32_t firstParticle = 0;  ///< the origin of its sums
    };
    /// A run of one piece's particles in mPieceParticles, [begin, end).
    struct DampingChunk {
        uint32_t piece = 0, begin = 0, end = 0;
    };
    static constexpr size_t kDampingChunk = 4096;
    bool mPiecesStale = true;
    std::vector<DampedPiece> mDampedPieces;
    std::vector<uint32_t> mPieceParticles;  ///< the particles piece by piece, each in particle order
    std::vector<DampingChunk> mDampingChunks;
    void findDampedPieces();
    /// Per particle, the fewest intact bonds between it and a held particle (UINT32_MAX: none):
    /// a held piece is a cantilever as long as its farthest particle's path, plus half a voxel
    /// to its free face (a wall held along its base, its height, not its length).
    std::vector<uint32_t> bondsFromHeld() const;
    /// Each free piece's particles' velocities and spins about the piece's rigid motion (the
    /// motion with their linear and angular momentum, about their centre, with their present
    /// inertia) decay by exp(−2 ζ ω dt); so do a held piece's velocities. Momenta are unchanged.
    void dampVibration(double dtS);
    /// Per bond, 1 while it has snapped at its peak in this substep and not yet given back its
    /// energy (releaseSnapEnergies); apart from the terms, which it would make 7 % larger.
    std::vector<uint8_t> mSnapped;

    /// Each particle's tr ε: per axis, the mean stretch (length change / h) of its bonds along it.
    void computeVolumetricStrain();
    /// A bond's strain, damage (grown over dtS when `growDamage`) and force terms, from the
    /// state; writes only the bond's own entries, so bonds measure in parallel. Returns what
    /// happened to it (kSnapped, kBroke).
    uint8_t measureBond(size_t b, double dtS, bool growDamage);
    /// What measureBond reports: the bond snapped at its peak (releaseSnapEnergies), or broke
    /// by any law (the pieces may have changed).
    static constexpr uint8_t kSnapped = 1, kBroke = 2;
    /// A bond's spring, bending and twisting energy at a strain, for its stiffness times
    /// `intact` (unit: J).
    double elasticEnergyJ(size_t b, const BondStrain& strain, double intact) const;
    /// Whether a bond breaks at its peak: its strength class's voxels are too large to soften
    /// (Strength::peakStretchM), whatever its own strength scale.
    bool snapsAtPeak(size_t b) const;
    /// A bond that snaps at its peak loses its whole elastic energy, where a crack dissipates
    /// only Gf per area (ft² h / 2E against Gf: nine times more for glass at 5 mm). The rest is
    /// what a running crack releases into the material around it: each bond that snapped this
    /// substep pushes its two particles apart along it with exactly that kinetic energy (equal
    /// and opposite impulses along their line, so momentum and angular momentum are unchanged),
    /// so a crack dissipates Gf per area at any voxel size, as the crack band does below it.
    /// One at a time in bond order, at the substep's end.
    void releaseSnapEnergies();
    /// One bond's release: its spring, bending and twisting energy (closed, less its normal
    /// spring's, which stays as contact) and `volumetricJ`, its share of what its stretch held
    /// in its particles' volumetric terms, at its failure surface, less Gf h².
    void releaseSnapEnergy(size_t b, double volumetricJ);
    /// A support bond's bearing load (LatticeModel::bearingLoads) from its box's pressure.
    void recordBearingLoad(size_t supportBond, int face, double pressurePa, const Eigen::Quaterniond& bodyToWorld);
    /// The lattice in equilibrium with its dead loads before anything else acts (fromBody): its
    /// weight (`weightPerParticleN` on each free voxel particle, as setExternalForces applies it)
    /// and its supports' bearing loads along the columns of particles along the body's axis
    /// nearest the weight, each column standing on a support taking down what lies on it. Exact
    /// for a prism on its base; a column over a gap, and loads across the columns, start
    /// unloaded and settle dynamically as before (docs/accuracy.md).
    void settleUnderDeadLoads(const Eigen::Vector3d& weightPerParticleN);
    /// The bearing loads' mean direction (world frame).
    Eigen::Vector3d bearingDirection() const;
    /// Each particle's dead load along the way down (unit: N).
    std::vector<double> deadLoadsAlong(const Eigen::Vector3d& weightPerParticleN, const Eigen::Vector3d& downWorld) const;
    /// Per particle, what its bond below carries, how far it has moved down, and how far its
    /// sides spread per unit of their distance from its layer's centre (unit: N, m, 1).
    struct ColumnLoads {
        std::vector<double> carriedN, shorteningM, lateralStrain;
    };
    /// The loads taken down the columns along `axis` (down: its `sign`) to the supports.
    ColumnLoads takeDownLoads(int axis, int sign, const std::vector<double>& loadN) const;
    /// The shortenings and spread of one column, from its top particle down (takeDownLoads).
    void shortenColumn(uint32_t top, int axis, int faceBelow, ColumnLoads& columns) const;
    /// How much a particle's sides spread per unit of its strain along the axis under uniaxial
    /// stress along it (its Poisson ratio in the lattice, with its condensed λ).
    double lateralPoissonRatio(uint32_t p, int axis) const;
    /// Each particle's move into equilibrium in the body frame: down its column, and its sides
    /// out from its layer's centre; supports beside a voxel move with it (unit: m).
    std::vector<Eigen::Vector3d> settlingMoves(int axis, int sign, const ColumnLoads& columns) const;
    void recordSettledStrainEnergies();
    /// Each bond starts with the damage its body's links remember (Body::linkDamage; fromBody).
    void takeOverLinkDamage(const Body& body);
    /// A bond starts at damage D: on its softening line where the secant stiffness is 1 − D
    /// (the rate law's strength factor back at 1, as its history before is not kept), and with
    /// Davison–Stevens damage D.
    void startDamaged(size_t b, double damage);
    /// The failure index's factors (LatticeModel::failureTerms), from the stiffness.
    void computeFailureTerms();
    /// The failure index as a stretch (equivalentStretchM) from a measured strain and the
    /// bond's damage.
    double equivalentStretchM(size_t b, const BondStrain& strain, double lengthM, double damage) const;
    /// Damage grows with the largest equivalent stretch (and under Davison–Stevens, over the
    /// step's duration); what it takes away stays away. Returns whether the damage may have
    /// changed.
    bool growBondDamage(size_t b, double equivalentStretchNowM, double strainRatePerS, double dtS);
    /// The rate law's strength factor follows an increase of a bond's stretch while the bond is
    /// undamaged (BondHistory::strengthFactor).
    void followStrengthRate(BondHistory& history, double increaseM, double strainRatePerS) const;
    /// A bond's softening line: its peak stretch u0 and the stretch uf where it carries nothing,
    /// for its strength scale s and strength factor f: s f u0 and uf / (s f), so the energy under
    /// it, ½ k u0 uf, is the material's Gf h² whatever the scatter and the rate (unit: m).
    std::pair<double, double> softeningLineM(size_t b) const;
    /// 0 intact … 1 broken on the softening line, from the largest equivalent stretch.
    double softeningDamage(size_t b) const;
    /// Davison–Stevens: a bond's damage after dtS, at its equivalent stretch now.
    double rateDamageAfter(size_t b, double equivalentStretchNowM, double dtS) const;
    /// Adds the volumetric term to the bond's force on high, once every particle's volumetric
    /// strain is known, and takes the pair's moment (so a bond's force is found once, not once
    /// from each end).
    void completeBondForce(size_t b);
    /// A particle's bond force and moment: the sum over its faces, in face order.
    void gatherBondForces(size_t p);
    // Building (fromBody).
    /// Static boxes the particles may not pass through (the scene's colliders: a window's frame).
    /// A particle whose cube sinks into one by more than a quarter of its edge is put back at that
    /// depth and loses its velocity into the box, as on the ground. The quarter leaves a support
    /// bond's elastic give alone and matches the rigid phase's tolerance
    /// (collisions.penetration_tolerance_voxels' default).
    void keepOutOf(const StaticWorld& supports);
    void addParticle(const openvdb::Coord& ijk, const Eigen::Vector3d& placeM, const Eigen::Vector3d& velocity, const Eigen::Vector3d& spin,
                     const Eigen::Quaterniond& q, bool isHeld);
    void addVoxelParticles(const Body& body);
    /// A bond from `low` to its +axis neighbour `high`.
    void addBond(uint32_t low, uint32_t high, int axis);
    void addLinkBonds(const Body& body);
    /// Bonds each anchored voxel to a held point beyond it (fromBody).
    void addSupportBonds(const Body& body, const StaticWorld& supports);
    /// The face of an anchored voxel that a support holds (face -1: none) and the box holding it
    /// (-1: the ground): the ground's face when the voxel lies within half a voxel of it, else
    /// the free face whose neighbouring cell's centre lies deepest inside a box
    /// (freeFaceDeepestInBoxes).
    FaceInBox supportedFace(const Body& body, uint32_t p, int groundFace, const std::vector<ObstacleBox>& boxes) const;
    /// Bonds between two voxels of the same masonry unit take the unit's strength (Material),
    /// when a voxel is no taller than a course.
    void classifyUnitBonds(const Material& material);
    /// Bonds along the grain of a material with one take its strength along the grain.
    void classifyGrainBonds(const Material& material);
    void condenseVolumetricModulus();
    /// Each bond's strength scale: a lognormal of mean 1 whose CoV is the material's, reduced
    /// by averaging over the bond's h x h face (the variance function, squared), drawn from a
    /// Gaussian random field at the bond's midpoint in the body's index space (so pieces keep
    /// their strengths through splits).
    void scatterStrengths(const Material& material, uint64_t seed);
    /// f(i) for i < count: in parallel for large lattices, in order for small ones.
    template <typename F>
    void forEach(size_t count, const F& f) const;
    /// Puts a particle that sank into a collider back to the allowed depth (keepOutOf), with
    /// the box's friction (pushOut).
    void keepOutOfColliders(size_t p);
    /// Puts a particle that sank into the ground back on it (GroundPlane), with its friction.
    void keepAboveGround(size_t p);
    /// Moves a particle `depthM` out along `outward` and takes away its speed into the surface
    /// and, by Coulomb's law, up to `friction` times that speed along it: the impulse that stops
    /// it sinking bounds the impulse that stops it sliding, so a particle pressed on a surface
    /// by a force N slides to rest under μ N (applied at its centre: a cube's contact would
    /// also turn it; its bonds hold it from turning in a lattice).
    void pushOut(size_t p, const Eigen::Vector3d& outward, double depthM, double friction);
    /// Whether a particle is still bonded to its ground point: it then bears on the ground
    /// through that bond, and the plane (a plastic contact at its rest height) would hold the
    /// compression side of a bent base rigid, stiffening and strengthening it.
    bool bondedToGround(size_t p) const;
    BondStrain strainOf(const LatticeBond& bond) const;

    // Contact between particles that share no bond (LatticeContact.cpp): pieces of one lattice
    // that were never neighbours meet as the broken bonds' pieces do, by a normal spring along
    // the line of centres while their cubes' centres are closer than an edge.
    /// Particle pairs sharing no bond whose centres were within an edge plus kContactSkin
    /// edges when last listed, p < q, sorted: a Verlet list, listed again once a particle has
    /// moved half the skin, so it holds every pair that can touch.
    std::vector<std::pair<uint32_t, uint32_t>> mContactCandidates;
    /// Where the particles were when the candidates were listed (empty: list them afresh).
    std::vector<Eigen::Vector3d> mListedAtM;
    /// Lists the candidates again if a particle has moved half the skin since they were listed.
    void updateContactCandidates();
    void listContactCandidates();
    /// Whether particles p and q share a bond (intact or broken: a broken bond carries their
    /// compression itself).
    bool shareABond(uint32_t p, uint32_t q) const;
    /// Adds the contacts' forces to bondForceN.
    void addContactForces();
};

}  // namespace spall
