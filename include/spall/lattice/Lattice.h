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
#include <spall/lattice/LatticeModel.h>
#include <spall/loads/Exposure.h>
#include <spall/world/StaticWorld.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace spall {

struct BondStrainRun;  // src/lattice/BondStrainBatch.h

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
    /// scatter (Material::strengthDistribution); with `blocks` of more than one voxel, a
    /// particle per block (ParticleBlocks.h).
    static Lattice fromBody(const Body& body, const Material& material, const StaticWorld& supports = StaticWorld(),
                            const LatticeSettings& settings = LatticeSettings(), const VoxelBlocks& blocks = VoxelBlocks(), uint64_t seed = 1);

    size_t particleCount() const { return state.positionM.size(); }
    /// The particle at a voxel (a support point at the cell beyond its voxel), or -1.
    int32_t particleAt(const openvdb::Coord& ijk) const { return mModel.particleIndex->getValue(ijk); }
    /// The bond across a face of particle p (LinkBits.h's Face order), or -1.
    int32_t bondAcross(size_t p, int face) const { return mModel.bondAcross[p][face]; }
    size_t bondCount() const { return mModel.bonds.size(); }

    /// The step it takes (unit: s): 0.9 × 2/ω, ω the highest frequency of a lattice of its
    /// springs, in the bulk or at a face, edge or corner (highestFrequencyRadS).
    double stableTimeStepS() const;
    void step(double dtS);
    /// A step in two halves, for lattices stepped together (LatticePairContact.h), whose forces
    /// on each other are added to bondForceN between them: the first half-kick, the drift and
    /// the forces at the new places; then the second half-kick, the energy snapped bonds give
    /// back and the damping. step() is the two.
    void moveAndMeasure(double dtS);
    void finishStep(double dtS);
    /// Whether it may coast: no particle held, and the same external force on every particle
    /// (its weight, no blast). A lattice built from a rigid body and not stepped since is then
    /// unstrained, and stays so while nothing touches it.
    bool movesAsARigidBody() const;
    /// moveAndMeasure for a lattice that moves as the rigid body it was built from (only while
    /// movesAsARigidBody): its particles carried and turned with its rigid motion, keeping its
    /// momentum and angular momentum, no bond measured (each would find no strain), then the
    /// ground's and colliders' forces, so it learns when it meets them (pressedOnASurface).
    /// finishStep completes the step as after moveAndMeasure.
    void coast(double dtS);
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
    /// 0 intact … 1 broken: the secant stiffness lost in tension, shear and bending, by cracking
    /// (D_t) and crushing (D_c) together, 1 − (1 − D_t)(1 − D_c). In compression it carries
    /// 1 − D_c of its normal spring: a crack closes and carries again, as contact; what crushing
    /// took it does not.
    double bondDamage(size_t b) const;
    /// The traction it could still carry at its largest stretch so far, as a fraction of its
    /// peak: (1 − D) max(κ, u0) / u0; 0 once broken.
    double residualStrengthFraction(size_t b) const;
    /// Broken, or carrying less than LatticeModel::handOffResidualStrength of its peak: what a
    /// hand-off cuts.
    bool brokenAtHandOff(size_t b) const;
    /// D_c alone: 0 … 1 on the compressive softening line (Strength::compressiveStrengthPa).
    double crushingDamage(size_t b) const;
    /// The particles grouped by the bonds that have not broken.
    DisjointSets intactPieces() const;
    /// Whether any bond to a held particle is still unbroken: false once the whole lattice has
    /// let go of its supports (its anchored body then moves with it).
    bool heldBySupport() const;
    /// A piece's fundamental angular frequency, estimated as an Euler–Bernoulli beam's of
    /// thickness t and length L: free at both ends, ω = 22.37 √(EI / ρAL⁴) = 6.458 c t / L², or
    /// clamped at one, 3.516 √(EI / ρAL⁴) = 1.015 c t / L² (c = √(E / ρ)) (unit: rad/s). A free
    /// piece's t and L are the thinnest and longest sides of its box in the lattice's index
    /// space; a held piece's L is its farthest reach from what holds it (findDampedPieces).
    double fundamentalFrequencyRadS(double thicknessM, double lengthM, bool held) const;

    /// The softest bond's stiffness: a surface's spring, as if the surface were a half voxel of
    /// the body's own material behind the particle's half (unit: N/m).
    double surfaceStiffnessNPerM() const;
    /// What it was built with (fromBody), unchanged since.
    const LatticeModel& model() const { return mModel; }
    /// Whether the bond pass measures the bonds whose damage stays as it is this step side by
    /// side (BondStrainRun::steady; on unless turned off). Off, every bond takes the one-bond
    /// path (measureBond), which gives the same results bit for bit: a test compares them.
    void batchSteadyBonds(bool on) { mBatchesSteadyBonds = on; }
    /// How many bonds the last bond pass measured in its batches.
    size_t bondsBatchedInLastPass() const { return mBondsBatchedInLastPass; }
    /// The free (not held) particles' mass, their centre, and their inertia about it (their
    /// places' and each cube's own); the mass 0 where every particle is held.
    struct FreeMass {
        double massKg = 0.0;
        Eigen::Vector3d centreM = Eigen::Vector3d::Zero();
        Eigen::Matrix3d inertiaKgM2 = Eigen::Matrix3d::Zero();
    };
    FreeMass freeMass() const;
    /// Whether a support bears on its voxel: while they touch, its bond broken or not (a floor
    /// rests on a cracked head), the voxel within a quarter voxel of where the support held it.
    bool bears(const LatticeModel::BearingLoad& load) const;
    /// Whether the ground or a collider has pushed any of its particles since it was built (its
    /// forces at build count too; addSurfaceForces; a bearing support does not count): a lattice
    /// that entered for an impact has then met what it struck.
    bool pressedOnASurface() const { return mPressedOnASurface; }

private:
    LatticeModel mModel;

    // A step's scratch, found again from the model and the state (never saved).
    // Per particle: tr ε and λ tr ε / (bonds along each axis).
    std::vector<double> mVolumetricStrain;
    std::vector<Eigen::Vector3d> mVolumetricStressShare;
    /// What crushing reads (sized by refreshForces for a material that crushes, else empty):
    /// per particle, λ tr ε as its material would carry it uncrushed; per bond, the normal
    /// stress it carried when its force was last completed, tension positive (unit: Pa).
    std::vector<double> mUncrushedLambdaTracePa;
    std::vector<double> mBondNormalStressPa;
    /// What the force pass takes from each bond, measured once per substep (measureBonds); the
    /// arm between its particles is found again from their places where it is needed.
    struct BondForceTerms {
        /// On high: the spring and dashpot, before the volumetric term (unit: N).
        Eigen::Vector3d forceOnHighN;
        Eigen::Vector3d bendingMomentNm;  ///< bending and twisting, on high (unit: N m)
        /// The volumetric force on high per pascal of its particles' shares, along −arm:
        /// h² √(1 − D in tension, 1 − D_c in compression) / |arm| (unit: m).
        double volumetricAreaPerArmM = 0.0;
    };
    std::vector<BondForceTerms> mBondTerms;
    /// Each bond's stretch as the volumetric strain counts it, apart from the force terms so
    /// the volumetric pass reads 16 bytes a bond (inside the terms it read at their stride).
    struct BondStretch {
        /// Its length change: in tension times √(1 − D), so the bond's own share of the
        /// volumetric force falls with 1 − D as its spring's does and the traction follows the
        /// softening line; in compression times √(1 − D_c), as crushing takes the volumetric
        /// share too (unit: m).
        double effectiveM = 0.0;
        /// The same without crushing's factor: what the material would strain uncrushed (unit: m).
        double uncrushedM = 0.0;
    };
    std::vector<BondStretch> mBondStretch;
    // Damping (dampVibration): the pieces as the last bond to break left them, each with the
    // decay rate of its velocities about its rigid motion, 2 ζ ω (Clough & Penzien, Dynamics
    // of Structures, 1993, §12-4: mass-proportional damping a0 M damps mode n at a0 / 2 ω_n).
    struct DampedPiece {
        bool held = false;
        bool heldByVoxels = false;  ///< some of its own voxels are held (no support bond between)
        double decayPerS = 0.0;
        uint32_t firstParticle = 0;  ///< the origin of its sums
        /// A held piece turned further than this from rest is no longer held elastically: its
        /// support has opened into a hinge (openSupportHinges) (unit: rad).
        double hingeRotationRad = 0.0;
        /// Its bonds to supports that had not broken when the pieces were found: a run of
        /// mPieceSupportBonds, [firstSupportBond, endSupportBond).
        uint32_t firstSupportBond = 0, endSupportBond = 0;
        /// Its particles: a run of mPieceParticles, [firstMember, endMember).
        uint32_t firstMember = 0, endMember = 0;
    };
    /// A run of one piece's particles in mPieceParticles, [begin, end).
    struct DampingChunk {
        uint32_t piece = 0, begin = 0, end = 0;
    };
    static constexpr size_t kDampingChunk = 4096;
    bool mPiecesStale = true;
    bool mBatchesSteadyBonds = true;  ///< batchSteadyBonds
    size_t mBondsBatchedInLastPass = 0;
    /// What happened to bonds in the step under way (kSnapped, kBroke): moveAndMeasure's, for finishStep.
    uint8_t mStepEvents = 0;
    bool mPressedOnASurface = false;  ///< pressedOnASurface
    /// Velocity Verlet's half-kick of a step: dt/2 over a particle's mass and inertia.
    struct HalfKick {
        double perMass, perInertia;
    };
    HalfKick halfKick(double dtS) const;
    /// The half-kick of one particle by its forces.
    void kickParticle(size_t p, const HalfKick& kick);
    std::vector<DampedPiece> mDampedPieces;
    std::vector<uint32_t> mPieceParticles;  ///< the particles piece by piece, each in particle order
    std::vector<uint32_t> mPieceSupportBonds;  ///< the held pieces' support bonds, piece by piece
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
    /// A held piece whose support has cracked and which has turned as a whole (its particles'
    /// best-fit rotation, Kabsch; not one on a line, nor one held by its own voxels) further than
    /// its intact support would let it turn elastically
    /// (DampedPiece::hingeRotationRad) moves as a mechanism about its support, not as a
    /// vibration about rest: its support bonds break, it is a free piece resting on its support
    /// (contact and friction, as any broken bond), and damping no longer holds it at rest
    /// (issue 48). Returns whether any did.
    bool openSupportHinges();
    /// Whether a held piece has turned past its hinge rotation.
    bool turnedPastHinge(const DampedPiece& piece) const;
    /// Each piece's support bonds not yet broken (findDampedPieces' last part).
    void findSupportBondsOfPieces(const std::vector<int32_t>& pieceOfRoot, DisjointSets& sets);
    /// Breaks a bond outright: its damage is 1 by cracking (contact in compression only).
    void breakBond(size_t b);
    /// Per bond, 1 once its damage has reached 1 (bondDamage): set where damage grows
    /// (measureBond, breakBond) and found again by refreshForces, so the passes that ask which
    /// bonds hold (the pieces, the support, the ground) read a byte a bond, not its history.
    std::vector<uint8_t> mBroken;
    bool isBroken(size_t b) const { return mBroken[b] != 0; }
    /// Per bond, 1 while it has snapped at its peak in this substep and not yet given back its
    /// energy (releaseSnapEnergies); apart from the terms, which it would make 11 % larger.
    std::vector<uint8_t> mSnapped;

    /// Each particle's tr ε: per axis, the mean stretch (length change / h) of its bonds along it.
    void computeVolumetricStrain();
    /// Every bond's strain, damage (grown over dtS when `growDamage`) and force terms, from the
    /// state, in runs of consecutive bonds whose strains, and the terms of those that stay
    /// elastic, are measured side by side (BondStrainBatch.h). Returns what happened to any
    /// (kSnapped, kBroke).
    uint8_t measureBonds(double dtS, bool growDamage);
    /// One bond's damage and force terms, its strain lane `lane` of `run`; writes only the bond's
    /// own entries, so bonds measure in parallel. Returns what happened to it.
    uint8_t measureBond(size_t b, const BondStrainRun& run, size_t lane, double dtS, bool growDamage);
    /// A bond's terms as the batch measured them, for a bond that stays on its elastic line.
    void takeSteadyTerms(size_t b, const BondStrainRun& run, size_t lane);
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
    void recordBearingLoad(size_t supportBond, int face, double pressurePa, double friction, const Eigen::Quaterniond& bodyToWorld);
    /// The lattice in equilibrium with its dead loads before anything else acts (fromBody): its
    /// weight (`weightPerParticleN` on each free voxel particle, as setExternalForces applies it)
    /// and its supports' bearing loads along the columns of particles along the body's axis
    /// nearest the weight, each column standing on a support taking down what lies on it. Exact
    /// for a prism on its base; a column over a gap, and loads across the columns, start
    /// unloaded and settle dynamically as before (docs/accuracy.md). Moves the particles only:
    /// the caller refreshes the forces. Returns whether there was anything to settle (a body
    /// held by nothing falls as it is).
    bool settleUnderDeadLoads(const Eigen::Vector3d& weightPerParticleN);
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
    /// The axes across `axis` along which a particle has bonds.
    int lateralAxesWithBonds(uint32_t p, int axis) const;
    /// How much a particle's sides spread per unit of its strain along the axis under uniaxial
    /// stress along it (its Poisson ratio in the lattice, with its condensed λ).
    double lateralPoissonRatio(uint32_t p, int axis) const;
    /// Each particle's move into equilibrium in the body frame: down its column, and its sides
    /// out from its layer's centre; supports beside a voxel move with it (unit: m).
    std::vector<Eigen::Vector3d> settlingMoves(int axis, int sign, const ColumnLoads& columns) const;
    /// LatticeModel::settledStrainJ from the settled state's forces.
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
    /// (A BondStrain, or a view of one with its members' names.)
    template <typename Strain>
    [[gnu::always_inline]] inline double equivalentStretchM(size_t b, const Strain& strain, double lengthM, double damage) const;
    /// Damage grows with the largest equivalent stretch (and under Davison–Stevens, over the
    /// step's duration), crushing with the largest crushing shortening; what they take away
    /// stays away. Returns whether the damage may have changed.
    inline bool growBondDamage(size_t b, double equivalentStretchNowM, double crushingShorteningNowM, double strainRatePerS, double dtS);
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
    /// Whether either strength class crushes (Strength::compressiveStrengthPa).
    bool canCrush() const;
    /// How near a bond is to crushing, as a shortening: its compression as its uncrushed
    /// material would carry it (its own normal strain `normalM` / h times d, and its
    /// particles' λ tr ε) over the Hoek–Brown strength at the confinement across it, times fc h
    /// / E (1 on the strength surface; its shortening in uniaxial compression). Where even the
    /// unconfined strength leaves it within the bond's largest shortening so far, that unconfined
    /// shortening, an upper bound that changes nothing (unit: m).
    inline double crushingShorteningM(size_t b, double normalM) const;
    /// The compression across axis `a` at a particle: of its normal stresses along the two axes
    /// across, each its bonds' mean, the lesser; 0 in tension or at a free face (unit: Pa).
    inline double confinementPa(uint32_t p, int a) const;
    /// A bond's whole force on high: its spring and dashpot with the volumetric term, once every
    /// particle's volumetric strain is known (the same from either end, so each end finds it).
    [[gnu::always_inline]] inline Eigen::Vector3d completeBondForce(size_t b, const Eigen::Vector3d& armM) const;
    /// A particle's bond force and moment: the sum over its faces, in face order, each bond's
    /// completed and with the moment of its pair of forces, −(arm / 2) × force, about either
    /// centre (it acts at the face between them; a pin at its voxel's centre). The low end of a
    /// bond records its normal stress for crushing.
    void gatherBondForces(size_t p);
    // Building (fromBody).
    /// Static boxes the particles may not pass through (the scene's colliders: a window's frame).
    /// A particle whose cube sinks into one by more than a quarter of its edge is pushed back
    /// elastically, as on the ground (pressOn). The quarter leaves a support bond's elastic give alone and
    /// matches the rigid phase's tolerance (collisions.penetration_tolerance_voxels' default).
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
    /// Each bond's strength scale, by the material's distribution, keyed on the bond's place in
    /// the body's index space (so pieces keep their strengths through splits).
    void scatterStrengths(const Material& material, uint64_t seed);
    /// Lognormal: mean 1, the CoV reduced by averaging over the bond's h x h face (the variance
    /// function, squared), from a Gaussian random field at the bond's midpoint; for the bonds
    /// `scatters` picks.
    template <class Picks>
    void scatterLognormal(double coefficientOfVariation, double correlationLengthM, uint64_t seed, const Picks& scatters);
    /// Weibull: each bond the weakest link of its h x h face, independently.
    void drawWeakestLinkStrengths(const Material& material, uint64_t seed);
    /// f(i) for i < count: in parallel for large lattices (`grain` items a task at least, by
    /// default core/Parallel.h's for cheap items), in order for small ones.
    template <typename F>
    void forEach(size_t count, const F& f) const;
    template <typename F>
    void forEach(size_t count, const F& f, size_t grain) const;
    /// The ground's and the colliders' forces on every free particle that presses on them
    /// (LatticeStaticContacts.cpp), added to its bond force; `dtS` the step they act over.
    void addSurfaceForces(double dtS);
    /// A particle's push from the colliders it sinks into beyond the allowed depth (keepOutOf)
    /// and its slack. Returns whether any pushed it.
    bool pressOnColliders(size_t p, double dtS);
    /// How far a particle's cube sinks into a collider beyond the allowed depth, and the
    /// outward normal of the face it is nearest (none if outside the grown box).
    struct ColliderDepth {
        Eigen::Vector3d outward;
        double depthM;
    };
    std::optional<ColliderDepth> depthInCollider(size_t p, const LatticeModel::KeptOut& box) const;
    /// Each particle's slack in the colliders, from where it entered (LatticeModel::colliderSlackM).
    void measureColliderSlack();
    /// The friction of a support bearing on a voxel whose bond to it has broken (a floor on a
    /// cracked head holds it from sliding, as the ground holds its base).
    void holdByBearing(const LatticeModel::BearingLoad& load, double dtS);
    /// A particle's push from the ground its cube sinks into (GroundPlane). Returns whether it pushed.
    bool pressOnGround(size_t p, const LatticeModel::SurfaceContact& ground, double dtS);
    /// The ground's contact with each particle that presses on it through a step `dtS`: rigid,
    /// or compliant (GroundCompliance), its footing the patch of particles that press on it,
    /// shared.
    LatticeModel::SurfaceContact groundContact(double dtS) const;
    /// Free particles whose cubes sink into the ground (not those bonded to it).
    size_t particlesOnGround() const;
    /// The force of a surface on a particle whose cube sinks `depthM` into it along -`outward`:
    /// the spring and the dashpot, never pulling; and Coulomb's friction against its sliding, up
    /// to μ times that, or what stops the sliding within the step `dtS` (applied at its centre:
    /// a cube's contact would also turn it; its bonds hold it from turning in a lattice).
    /// Returns whether it pushed.
    bool pressOn(size_t p, const Eigen::Vector3d& outward, double depthM, const LatticeModel::SurfaceContact& surface, double dtS);
    /// Whether a particle is still bonded to its ground point: it then bears on the ground
    /// through that bond, and the plane would hold the compression side of a bent base rigid,
    /// stiffening and strengthening it.
    bool bondedToGround(size_t p) const;
    // The bond pass's per-bond functions are inline (src/lattice/LatticeBondLaws.h).
    [[gnu::always_inline]] inline BondStrain strainOf(const LatticeBond& bond) const;
    /// From a bond's low particle to its high one (unit: m).
    Eigen::Vector3d armOf(size_t b) const { return state.positionM[mModel.bonds[b].high] - state.positionM[mModel.bonds[b].low]; }
    /// The strength a bond fails at.
    const LatticeStiffness::Strength& strengthOf(size_t b) const { return mModel.stiffness.strength[mModel.bonds[b].strengthClass]; }

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
