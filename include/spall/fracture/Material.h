// Materials in physical units, with presets calibrated on published blast-damage tables.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace spall {

/// How a material's strength rises with the rate it is strained at.
enum class StrengthRateLaw {
    None,
    /// fib Model Code 2010 (5.1.11.2), concrete in tension: (ε̇/ε̇0)^0.018 up to 10 1/s, then
    /// 0.0062 (ε̇/ε̇0)^(1/3), ε̇0 = 1e-6 1/s.
    FibModelCode2010,
};
template <>
struct EnumNames<StrengthRateLaw> {
    static constexpr std::pair<StrengthRateLaw, const char*> kNames[] = {{StrengthRateLaw::None, "none"},
                                                                         {StrengthRateLaw::FibModelCode2010, "fib-mc2010"}};
};

/// How the deformable phase's bonds scatter in strength (Material::strengthDistribution).
enum class StrengthDistribution {
    /// A lognormal field correlated in space (lattice/RandomField.h): strength set by a
    /// material's structure at some scale, as concrete's by its aggregate.
    Lognormal,
    /// Independent bonds, each the weakest link of its face (Weibull): strength set by the
    /// worst flaw, as glass's by surface flaws.
    Weibull,
};
template <>
struct EnumNames<StrengthDistribution> {
    static constexpr std::pair<StrengthDistribution, const char*> kNames[] = {{StrengthDistribution::Lognormal, "lognormal"},
                                                                              {StrengthDistribution::Weibull, "weibull"}};
};

/// Which horizontal axis a masonry unit's length lies along (its courses are along z).
enum class UnitLengthAxis { X, Y };
template <>
struct EnumNames<UnitLengthAxis> {
    static constexpr std::pair<UnitLengthAxis, const char*> kNames[] = {{UnitLengthAxis::X, "x"}, {UnitLengthAxis::Y, "y"}};
};

/// How masonry units are laid (each pattern's courses along z from z = 0): running (stretcher)
/// bond, every unit along the wall, each course shifted half a unit; English bond, courses of
/// stretchers and of headers (units across the wall) in turn, headers shifted a quarter unit;
/// Flemish bond, a header after each stretcher in every course, each header centred on the
/// stretcher below.
enum class BondPattern { Running, English, Flemish };
template <>
struct EnumNames<BondPattern> {
    static constexpr std::pair<BondPattern, const char*> kNames[] = {
        {BondPattern::Running, "running"}, {BondPattern::English, "english"}, {BondPattern::Flemish, "flemish"}};
};

/// The axis a wood's grain (its fibres) runs along, in the object's frame at voxelisation; none:
/// the material is the same in every direction.
enum class GrainAxis { None, X, Y, Z };
template <>
struct EnumNames<GrainAxis> {
    static constexpr std::pair<GrainAxis, const char*> kNames[] = {
        {GrainAxis::None, "none"}, {GrainAxis::X, "x"}, {GrainAxis::Y, "y"}, {GrainAxis::Z, "z"}};
};

/// The dynamic increase factor of strength at a strain rate (unit: 1/s); 1 below the quasi-static rate.
double dynamicIncreaseFactor(StrengthRateLaw law, double strainRatePerS);

struct Material {
    std::string name;
    double densityKgM3 = 2000.0;        ///< (unit: kg/m^3)
    double meanYieldPa = 50e3;          ///< mean link yield limit, as side-on overpressure (unit: Pa)
    double yieldVariation = 0.1;        ///< limits are uniform in mean * [1 - v, 1 + v] (unit: fraction)
    double weakeningFraction = 0.2;     ///< limit reduction after an earlier charge loaded the link (unit: fraction)
    double orientationFactor = 0.1;     ///< limit * (1 - f |link . wave|) (unit: fraction; 0 turns it off)
    double damageRatePerS = 300.0;      ///< Davison–Stevens B in rate form (unit: 1/s)
    double damageStressScalePerPa = 0;  ///< Davison–Stevens C (unit: 1/Pa); 0 means 1 / meanYieldPa
    // What the deformable phase (fracture.algorithm "lattice") reads: elasticity, and the
    // tensile strength and fracture energy of its bonds' softening.
    double youngsModulusPa = 30e9;        ///< (unit: Pa)
    double poissonRatio = 0.2;            ///< (unit: 1)
    double tensileStrengthPa = 3e6;       ///< (unit: Pa)
    double fractureEnergyJPerM2 = 100.0;  ///< energy a crack dissipates per unit of its area, Gf (unit: J/m^2)
    /// Mohr–Coulomb with a tension cut-off: a plane fails in shear when |τ| > c + μ·(compression
    /// across it); c is the shear strength at no normal stress (unit: Pa) ...
    double shearStrengthPa = 6e6;
    double frictionCoefficient = 0.5;  ///< ... and μ = tan φ (unit: 1)
    /// Crushing (the deformable phase): the uniaxial compressive strength (concrete's fcm,
    /// masonry's fk, which is the assembly's, joints and units alike; wood's across the grain)
    /// and Gc, the energy a crushed band dissipates per unit of its area (crack band in
    /// compression). A strength of 0: it never crushes (unit: Pa, J/m^2).
    double compressiveStrengthPa = 0.0;
    double compressiveFractureEnergyJPerM2 = 0.0;
    StrengthRateLaw strengthRateLaw = StrengthRateLaw::None;
    /// The deformable phase's bonds scatter in strength (tension, shear and crushing together)
    /// about the values above, drawn from the scene's seed.
    StrengthDistribution strengthDistribution = StrengthDistribution::Lognormal;
    /// Lognormal: the coefficient of variation at the scale of the correlation length, the
    /// joints' for masonry; 0: every bond alike (unit: fraction) ...
    double strengthCoefficientOfVariation = 0.0;
    double strengthCorrelationLengthM = 0.02;  ///< ... (unit: m)
    /// ... and masonry's units', from a field of their own (unit: fraction).
    double unitStrengthCoefficientOfVariation = 0.0;
    /// Weibull: the modulus m, and the area whose median strength in uniform tension the
    /// strengths above are: an area A fails under a uniform σ with probability
    /// 1 − exp(−ln 2 (A / A_ref) (σ / ft)^m) (unit: 1, m^2).
    double strengthWeibullModulus = 0.0;
    double strengthReferenceAreaM2 = 1.0;
    /// The material's own damping as a fraction of critical, at a piece's fundamental mode: in
    /// the deformable phase each piece's vibration about its rigid motion decays at this ratio
    /// (Lattice::dampVibration); cracks and joints dissipate on their own, so it is the
    /// uncracked material's. 0: undamped (unit: 1).
    double dampingRatio = 0.0;
    // Masonry: an object of the material is built of units (bricks) laid in a bond pattern, in
    // courses along z from z = 0, the length axis along the wall (BondPattern). The
    // strengths above are then the joints' (the unit–mortar bond), those below the units'; a
    // bond between two voxels whose centres lie in different units crosses a joint. Elasticity
    // stays the assembly's. A unit length of 0 means a homogeneous material.
    double unitLengthM = 0.0;      ///< (unit: m)
    double unitWidthM = 0.0;       ///< across the wall (unit: m)
    double unitHeightM = 0.0;      ///< (unit: m)
    double jointThicknessM = 0.0;  ///< mortar between units (unit: m)
    UnitLengthAxis unitLengthAxis = UnitLengthAxis::X;
    BondPattern bondPattern = BondPattern::Running;
    double unitTensileStrengthPa = 0.0;       ///< (unit: Pa)
    double unitFractureEnergyJPerM2 = 0.0;    ///< (unit: J/m^2)
    double unitShearStrengthPa = 0.0;         ///< (unit: Pa)
    double unitFrictionCoefficient = 0.0;     ///< (unit: 1)
    // Wood: transversely isotropic about a grain axis. The elastic and strength values above
    // are then those across the grain (E and ν of the plane across it, tension across it, shear
    // along it), those below along it (tension along the grain breaks fibres). A material may
    // have units or a grain, not both.
    GrainAxis grainAxis = GrainAxis::None;
    double alongGrainYoungsModulusPa = 0.0;          ///< E_L (unit: Pa)
    double alongGrainShearModulusPa = 0.0;           ///< G_LT, shear in planes holding the grain (unit: Pa)
    double alongGrainTensileStrengthPa = 0.0;        ///< (unit: Pa)
    double alongGrainFractureEnergyJPerM2 = 0.0;     ///< a crack across the fibres (unit: J/m^2)
    double alongGrainShearStrengthPa = 0.0;          ///< shear across the fibres (unit: Pa)
    double alongGrainCompressiveStrengthPa = 0.0;    ///< crushing along the fibres (unit: Pa)
    double alongGrainCompressiveFractureEnergyJPerM2 = 0.0;  ///< (unit: J/m^2)
    // The look of its pieces (the glTF's materials, docs/vfx.md): colours are linear RGB in
    // [0, 1], glTF's baseColorFactor; an artistic choice per preset, not a measurement.
    Eigen::Vector3d colourRgb = Eigen::Vector3d(0.45, 0.45, 0.45);          ///< its own surface (unit: 1)
    Eigen::Vector3d interiorColourRgb = Eigen::Vector3d(0.35, 0.35, 0.35);  ///< a crack through it, or through a unit (unit: 1)
    Eigen::Vector3d jointColourRgb = Eigen::Vector3d(0.45, 0.43, 0.38);     ///< a crack along a joint: the mortar (unit: 1)
    double roughness = 0.9;     ///< glTF's roughnessFactor (unit: 1)
    double transmission = 0.0;  ///< light passing through (KHR_materials_transmission; glass) (unit: 1)
    /// Where the numbers come from.
    std::string source;
};

/// Whether a material is built of units (Material's masonry fields).
inline bool hasUnits(const Material& m) { return m.unitLengthM > 0.0; }

/// Whether the deformable phase's bonds of a material scatter in strength.
inline bool scattersInStrength(const Material& m)
{
    return m.strengthDistribution == StrengthDistribution::Weibull || m.strengthCoefficientOfVariation > 0.0 || m.unitStrengthCoefficientOfVariation > 0.0;
}

/// Whether a material has a grain (Material's wood fields).
inline bool hasGrain(const Material& m) { return m.grainAxis != GrainAxis::None; }

/// The index (0 x, 1 y, 2 z) of a material's grain axis, or -1 without a grain.
inline int grainAxisIndex(const Material& m) { return hasGrain(m) ? int(m.grainAxis) - int(GrainAxis::X) : -1; }

/// What a material built of units, or with a grain, lacks: the key and why; an empty key when
/// it lacks nothing.
struct FieldProblem {
    std::string key, reason;
};
FieldProblem structureProblem(const Material& m);

/// The unit a point lies in, as its indices (along the length axis, across it, course), for a
/// material built of units; the point in the object's world frame at voxelisation (unit: m).
std::array<int64_t, 3> masonryUnitOf(const Material& material, double xM, double yM, double zM);

/// Whether two points (the object's frame at voxelisation, unit: m) lie in different units of a
/// material built of units: a bond or a crack between them runs through a joint. False for a
/// material without units.
bool acrossJoint(const Material& material, const Eigen::Vector3d& aM, const Eigen::Vector3d& bM);

/// Whether particles of this size resolve a masonry material's units: no taller than a course
/// (else it is homogenised masonry: acrossCoursesStrengthRatio).
inline bool unitsResolvedBy(const Material& m, double particleM) { return particleM <= m.unitHeightM + m.jointThicknessM; }

/// Masonry seen at a scale coarser than a course (a homogenised material): how many times its
/// joints' tensile strength it takes to open a crack across the courses (a plane perpendicular
/// to the bed joints). Such a crack either steps, through the head joints in tension and along
/// the bed joints in shear over the units' overlap, or runs straight, through head joints and
/// units in alternate courses (the two failures of Backes' 1985 tests, as Lourenço 1996 ch. 3
/// describes them); the lesser of the two, per course height. A crack along the bed joints
/// stays the joints'.
double acrossCoursesStrengthRatio(const Material& material);

/// The P-wave speed, √(E (1 − ν) / ((1 + ν)(1 − 2ν) ρ)): a plane wave's in the bulk (unit: m/s).
double pWaveSpeedMS(const Material& m);

/// The slowest normal impact on a rigid surface that may damage a piece of the material: a flat
/// impact at v puts σ = ρ c v into the face that strikes (c the P-wave speed: the one-dimensional
/// impact of elastic wave theory, Kolsky, Stress Waves in Solids, 1963, ch. 4); an edge or a corner
/// that strikes first concentrates it, so this is an eighth of ft / (ρ c) (a concrete slab 3° off
/// flat takes no damage at it and some at twice it, tests/test_impact.cpp). ft is the weakest
/// tension the material carries (masonry's joints, wood across the grain) (unit: m/s).
double crackingImpactSpeedMS(const Material& m);

/// The named presets: glass, wood, brick-masonry, concrete, reinforced-concrete.
const std::vector<Material>& materialPresets();

/// A preset by name; throws InputError listing the known names.
const Material& findMaterialPreset(const std::string& name);

/// Keys and ranges of a material's numbers (src/fracture/Material.cpp); the name and the source
/// are not among them.
template <>
const std::vector<Field<Material>>& fieldTable<Material>();

/// Throws InputError naming the material and the field when a value is out of range.
void validateMaterial(const Material& material);

/// Builds a material whose walls start to break at the low end of a published failure range and
/// break completely at its high end (see docs/materials.md): with f = orientation factor,
/// mean (1 - v)(1 - f) = pLow and mean (1 + v) = pHigh.
Material calibrateMaterial(const std::string& name, double densityKgM3, double failureLowPa, double failureHighPa,
                           const std::string& source);

}  // namespace spall
