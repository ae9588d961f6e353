// Settings of the deformable phase (fracture.algorithm "lattice"): plain struct, a unit on every
// field.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>

namespace spall {

/// How a bond's damage grows.
enum class LatticeDamageLaw {
    /// Crack band: damage follows the largest failure index reached, on the softening line.
    Softening,
    /// Davison–Stevens in rate form, on real stresses: dD/dt = B [exp(C σx) − 1] with σx the
    /// bond's stress in excess of what the softening line allows at its largest failure index,
    /// so loaded slowly it follows the softening line (and dissipates Gf); loaded fast it
    /// carries more for a while (paper eq. 2.2 and 3.2, D* = 1 per bond; B and C fitted to the
    /// material's strain-rate law, which it replaces).
    DavisonStevens,
};
template <>
struct EnumNames<LatticeDamageLaw> {
    static constexpr std::pair<LatticeDamageLaw, const char*> kNames[] = {{LatticeDamageLaw::Softening, "softening"},
                                                                          {LatticeDamageLaw::DavisonStevens, "davison-stevens"}};
};

struct LatticeSettings {
    /// Linear bulk viscosity ζ: a dashpot of ζ ρ c h² along each bond (Lattice::bulkViscosity)
    /// (unit: 1).
    double bulkViscosity = 0.1;
    /// A body leaves the deformable phase once the blast has passed it and its vibration (strain
    /// energy plus kinetic energy about each piece's rigid motion) is below this fraction of
    /// ft² / (2E) times its volume, the elastic energy it would hold at its tensile strength
    /// throughout: stresses are then a tenth of the strength or less on average (unit: 1).
    double handoffEnergyFraction = 0.01;
    /// ... or at the latest this long after the blast has passed it, the vibration left then
    /// discarded and reported. Long enough for a wall's slowest bending mode to swing through
    /// once (a 2.5 m brick cantilever 0.3 m thick: 80 ms), since that swing is what breaks a
    /// wall at its base; vibration that outlasts it is rigid-body motion's loss (unit: s).
    double maxVibrationS = 0.1;
    /// A body in the phase is looked at for pieces quiet enough to leave once in each interval
    /// of this length (and when its time is up): a look measures every bond's energy and fits
    /// every piece's rigid motion, as much work as several lattice steps, and a piece that
    /// leaves a millisecond late has moved millimetres as a lattice instead (unit: s).
    double handoffCheckIntervalS = 0.001;
    /// At hand-off a bond still carrying less than this fraction of its peak traction counts as
    /// broken: a rigid body's link is whole or cut, and on a linear softening line such a crack
    /// has dissipated 1 − this fraction of its fracture energy (90 % at 0.1; damage is secant, so
    /// unloading returns to the origin)
    /// (Lattice::brokenAtHandOff) (unit: 1).
    double handoffResidualStrength = 0.1;
    /// How bonds' damage grows: the crack band's softening line, or Davison–Stevens in rate form
    /// above it, its B and C fitted to the material's strain-rate law (lattice/RateDamage.h).
    LatticeDamageLaw damageLaw = LatticeDamageLaw::Softening;
    /// A rigid body with links that strikes the ground or a collider faster than its material
    /// may take undamaged (crackingImpactSpeedMS) becomes a lattice for the impact, as a body the
    /// blast reaches does, and leaves the phase as any other once quiet (unit: none).
    bool impactFracture = false;
    /// While the blast (or the impact that made it a lattice) still loads it, a piece that has
    /// come free of its body's lattice (looked for once per handoff_check_interval_s) carries on
    /// as a lattice of its own, so that the blast
    /// loads its own faces, crack faces included, at its own place, and the wave passes the gaps
    /// between pieces (issue 48, item 3); otherwise the pieces stay one lattice, loaded on their
    /// whole body's faces at its rigid fit, until the blast has passed (unit: none).
    bool separateDuringBlast = false;
    /// The edge of a lattice particle, in voxels (lattice/ParticleBlocks.h): 1, a particle per
    /// voxel; k > 1, blocks of k³ voxels, k⁴ times less work, cracks and fragments as a lattice of
    /// k h resolves them, pieces in the voxels' shape (unit: voxels).
    int particleVoxels = 1;
};

// Keys and ranges (src/lattice/Settings.cpp).
template <>
const std::vector<Field<LatticeSettings>>& fieldTable<LatticeSettings>();

}  // namespace spall
