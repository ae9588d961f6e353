#include <spall/fracture/Material.h>

#include <spall/core/Error.h>

#include <cmath>
#include <string>

namespace spall {

double dynamicIncreaseFactor(StrengthRateLaw law, double strainRatePerS)
{
    switch (law) {
    case StrengthRateLaw::None:
        return 1.0;
    case StrengthRateLaw::FibModelCode2010: {
        // fib Model Code 2010, eqs. 5.1-108 and 5.1-109 (tension); the two branches meet at
        // 10 1/s (1.3366 and 1.3357).
        constexpr double kQuasiStaticPerS = 1e-6;
        const double ratio = strainRatePerS / kQuasiStaticPerS;
        if (ratio <= 1.0) return 1.0;
        return strainRatePerS <= 10.0 ? std::pow(ratio, 0.018) : 0.0062 * std::cbrt(ratio);
    }
    }
    return 1.0;
}

Material calibrateMaterial(const std::string& name, double densityKgM3, double failureLowPa, double failureHighPa,
                           const std::string& source)
{
    // Orientation factor: half of what the range allows, so the variation stays positive.
    Material m;
    m.name = name;
    m.densityKgM3 = densityKgM3;
    m.orientationFactor = 0.5 * (1.0 - failureLowPa / failureHighPa);
    const double lowBeforeOrientation = failureLowPa / (1.0 - m.orientationFactor);
    m.meanYieldPa = 0.5 * (failureHighPa + lowBeforeOrientation);
    m.yieldVariation = (failureHighPa - lowBeforeOrientation) / (2.0 * m.meanYieldPa);
    m.weakeningFraction = 0.25;
    m.damageRatePerS = 300.0;
    m.damageStressScalePerPa = 1.0 / m.meanYieldPa;
    m.source = source;
    return m;
}

namespace {

/// `m` with the elastic and fracture properties the deformable phase reads, and their source.
Material withElasticity(Material m, double youngsModulusPa, double poissonRatio, double tensileStrengthPa, double fractureEnergyJPerM2,
                        const std::string& source)
{
    m.youngsModulusPa = youngsModulusPa;
    m.poissonRatio = poissonRatio;
    m.tensileStrengthPa = tensileStrengthPa;
    m.fractureEnergyJPerM2 = fractureEnergyJPerM2;
    m.source += "; lattice: " + source;
    return m;
}

/// `m` with its own damping ratio (Material::dampingRatio) and the source.
Material withDamping(Material m, double dampingRatio, const std::string& source)
{
    m.dampingRatio = dampingRatio;
    m.source += "; damping: " + source;
    return m;
}

/// `m` with the look of its pieces: its own colour, a crack's through it (or through a unit) and,
/// for masonry, the mortar's along a joint (linear RGB); chosen by eye, not measured.
Material withLook(Material m, const Eigen::Vector3d& colourRgb, const Eigen::Vector3d& interiorColourRgb, const Eigen::Vector3d& jointColourRgb,
                  double roughness, double transmission = 0.0)
{
    m.colourRgb = colourRgb;
    m.interiorColourRgb = interiorColourRgb;
    m.jointColourRgb = jointColourRgb;
    m.roughness = roughness;
    m.transmission = transmission;
    return m;
}

/// `m` with bonds that scatter in strength (masonry's units by a CoV of their own), correlated over
/// `correlationLengthM`, and the source.
Material withScatter(Material m, double coefficientOfVariation, double correlationLengthM, const std::string& source, double unitCoefficientOfVariation = 0.0)
{
    m.strengthCoefficientOfVariation = coefficientOfVariation;
    m.unitStrengthCoefficientOfVariation = unitCoefficientOfVariation;
    m.strengthCorrelationLengthM = correlationLengthM;
    m.source += "; " + source;
    return m;
}

/// `m` with bonds each the weakest link of its face (Weibull of modulus `modulus`, its
/// strengths the median of `referenceAreaM2` in uniform tension), and the source.
Material withWeakestLink(Material m, double modulus, double referenceAreaM2, const std::string& source)
{
    m.strengthDistribution = StrengthDistribution::Weibull;
    m.strengthWeibullModulus = modulus;
    m.strengthReferenceAreaM2 = referenceAreaM2;
    m.source += "; " + source;
    return m;
}

/// `m` with its Mohr–Coulomb shear strength and friction, their source, and its rate law.
Material withShear(Material m, double shearStrengthPa, double frictionCoefficient, StrengthRateLaw rateLaw, const std::string& source)
{
    m.shearStrengthPa = shearStrengthPa;
    m.frictionCoefficient = frictionCoefficient;
    m.strengthRateLaw = rateLaw;
    m.source += "; shear: " + source;
    return m;
}

/// Gc / fc, the crushed band's ductility index Lourenço gives for masonry below 12 MPa
/// ("Structural masonry analysis: recent developments and prospects", 14th International Brick
/// and Block Masonry Conference, 2008); wood borrows it.
constexpr double kCrushingDuctilityM = 1.6e-3;

/// `m` crushing at a compressive strength with its fracture energy (Material::compressiveStrengthPa;
/// with a grain, those across it, then along it), and the source.
Material withCrushing(Material m, double compressiveStrengthPa, double fractureEnergyJPerM2, const std::string& source,
                      double alongGrainStrengthPa = 0.0, double alongGrainFractureEnergyJPerM2 = 0.0)
{
    m.compressiveStrengthPa = compressiveStrengthPa;
    m.compressiveFractureEnergyJPerM2 = fractureEnergyJPerM2;
    m.alongGrainCompressiveStrengthPa = alongGrainStrengthPa;
    m.alongGrainCompressiveFractureEnergyJPerM2 = alongGrainFractureEnergyJPerM2;
    m.source += "; crushing: " + source;
    return m;
}

/// `m` built of units: their size, the joint between them, their strength and fracture energy
/// (tension; in shear Rankine linearised, c = ft and μ = 0.5, as they fail by principal tension)
/// and the source.
Material withUnits(Material m, double lengthM, double widthM, double heightM, double jointM, double tensileStrengthPa,
                   double fractureEnergyJPerM2, const std::string& source)
{
    m.unitLengthM = lengthM;
    m.unitWidthM = widthM;
    m.unitHeightM = heightM;
    m.jointThicknessM = jointM;
    m.unitTensileStrengthPa = tensileStrengthPa;
    m.unitFractureEnergyJPerM2 = fractureEnergyJPerM2;
    m.unitShearStrengthPa = tensileStrengthPa;
    m.unitFrictionCoefficient = 0.5;
    m.source += "; units: " + source;
    return m;
}

/// `m` with a grain along `axis`: E, G, tensile strength, fracture energy and shear strength
/// along it, and the source.
Material withGrain(Material m, GrainAxis axis, double youngsModulusPa, double shearModulusPa, double tensileStrengthPa,
                   double fractureEnergyJPerM2, double shearStrengthPa, const std::string& source)
{
    m.grainAxis = axis;
    m.alongGrainYoungsModulusPa = youngsModulusPa;
    m.alongGrainShearModulusPa = shearModulusPa;
    m.alongGrainTensileStrengthPa = tensileStrengthPa;
    m.alongGrainFractureEnergyJPerM2 = fractureEnergyJPerM2;
    m.alongGrainShearStrengthPa = shearStrengthPa;
    m.source += "; grain: " + source;
    return m;
}

/// Mohr–Coulomb through a material's uniaxial compressive and tensile strengths:
/// fc = 2c cos φ / (1 − sin φ) and ft = 2c cos φ / (1 + sin φ) give c = √(fc ft) / 2 and
/// sin φ = (fc − ft) / (fc + ft) (Jaeger, Cook & Zimmerman, Fundamentals of Rock Mechanics, 4th
/// ed., 2007, §4.5). Returns {c, tan φ}.
std::pair<double, double> mohrCoulombThrough(double compressiveStrengthPa, double tensileStrengthPa)
{
    const double sinPhi = (compressiveStrengthPa - tensileStrengthPa) / (compressiveStrengthPa + tensileStrengthPa);
    return {0.5 * std::sqrt(compressiveStrengthPa * tensileStrengthPa), sinPhi / std::sqrt(1.0 - sinPhi * sinPhi)};
}

// Failure overpressures (the paper's rules): Clancey (1972), "Monitoring dangerous explosions",
// damage table as quoted widely (e.g. explosion-safety.jp "Damage from Blast (Clancey)"):
//   glass windows, large and small, usually shattered     3.4–6.9 kPa
//   wood panels (standard housing) fail, blow in           6.9–13.8 kPa
//   concrete or cinder block walls, not reinforced, shatter 13.8–20.7 kPa
//   brick panels 8–12 in thick, not reinforced, fail        48.2–55.1 kPa
// Reinforced concrete has no entry there (see reinforcedConcretePreset). Densities: typical
// values; concrete and reinforced concrete from EN 1991-1-1 Table A.1 (24 and 25 kN/m^3). Each
// preset below gives the sources of what the deformable phase reads (issues 17 and 18).
// Damping ratios: ENV 1998-6:2003 Annex B puts concrete elements at 2-7 % of critical and
// brickwork at 3-10 %; the lattice resolves the cracks and joints behind the upper ends, so the
// presets take the lower. Glass and wood: half the flexural loss factors Cremer & Heckl
// (Structure-Borne Sound, 1988) tabulate, 0.6-2 x 10^-3 for glass, about 10^-2 for wood.

/// EN 572-1 (E 70 GPa, ν 0.2, characteristic bending strength 45 MPa), Gf = KIc²/E with KIc =
/// 0.75 MPa m^0.5 (soda-lime glass, e.g. Wiederhorn 1969): 8 J/m². Glass fails by principal
/// tension, so in pure shear at τ = ft, and Rankine's criterion linearised at no normal stress
/// adds half the compression: c = ft, μ = 0.5. Its strength is a surface flaw's, so it scatters
/// as a weakest link: Weibull modulus 7 and k = 2.86e-53 N^-7 m^12 for a 60 s load (ASTM E1300's
/// glass failure prediction model, Beason & Morgan 1984, J. Struct. Eng. 110(2)), a median of
/// (ln 2 / k)^(1/7) = 30.4 MPa over 1 m². Static fatigue (σ^16 t constant, E1300's load
/// duration rule) raises it to 45 MPa for a load of 0.12 s, so EN 572-1's 45 MPa is kept as the
/// median of 1 m²; a blast's 1-30 ms would give 61-49 MPa (the preset has no rate law).
Material glassPreset()
{
    const Material glass = withDamping(withWeakestLink(withShear(withElasticity(calibrateMaterial("glass", 2500.0, 3.4e3, 6.9e3, "Clancey 1972: windows shatter at 3.4-6.9 kPa"),
                                                70e9, 0.2, 45e6, 8.0, "EN 572-1 (E, strength); Gf = KIc^2/E, KIc 0.75 MPa m^0.5"),
                                 45e6, 0.5, StrengthRateLaw::None, "Rankine (principal tension) linearised: c = ft, mu 0.5"),
                       7.0, 1.0, "Weibull m 7 (ASTM E1300 glass failure prediction model); ft the median of 1 m^2, E1300's for a 0.12 s load"),
                       0.001, "half the flexural loss factor of glass, 0.6-2 x 10^-3 (Cremer & Heckl 1988)");
    // Clear float glass, its broken edges the green of the pane seen edge-on.
    return withLook(glass, {0.80, 0.90, 0.87}, {0.35, 0.60, 0.50}, {0.35, 0.60, 0.50}, 0.05, 0.9);
}

/// Spruce, transversely isotropic about its grain (along z: a post): USDA Wood Handbook
/// FPL-GTR-190 (2010) ch. 5. Along the grain E_L about 10 GPa and G_LT = 0.0625 E_L (table 5-1,
/// Sitka spruce: G_LR/E_L 0.064, G_LT/E_L 0.061); tension along the grain 70 MPa, the modulus of
/// rupture (table 5-3a, Sitka spruce at 12 % moisture), which the handbook names a low estimate
/// of clear wood's tensile strength parallel to the grain; a crack across the fibres 10 kJ/m²
/// (Ashby & Jones, Engineering Materials 1, table 13.1: wood across the grain 8-20 kJ/m²); shear
/// across the fibres three times shear along them (Kollmann & Cote 1968, Principles of Wood
/// Science and Technology I, ch. 7). Across the grain E_T = 0.06 E_L (table 5-1: E_T/E_L 0.043,
/// E_R/E_L 0.078), ν 0.35 (ν_RT 0.435 and ν_TR 0.245), tension 2.5 MPa, Gf 250 J/m² (mode I,
/// TL; Stanzl-Tschegg, Tan & Tschegg 1995, Wood Sci. Technol. 29); shear parallel to the grain
/// 7.9 MPa (table 5-3b, Sitka spruce, 12 % moisture), no friction (the handbook gives none).
/// Crushing: table 5-3a's compression perpendicular and parallel to the grain; for Gc no
/// published value for wood was found, so it takes masonry's ductility index Gc / fc. Scatter:
/// CoV 0.25, table 5-6's for clear wood in tension along the grain (the JCSS Probabilistic Model
/// Code, part 3.5, puts tension across it at 2.5 times density's 0.10, the same), correlated over
/// 0.48 m, the mean length of a weak section along a Nordic spruce board (JCSS 3.5 after
/// Isaksson 1999).
Material woodPreset()
{
    constexpr double kAlongGrainPa = 10e9;
    const Material wood = withDamping(withGrain(withShear(withElasticity(calibrateMaterial("wood", 500.0, 6.9e3, 13.8e3, "Clancey 1972: wood panels fail at 6.9-13.8 kPa"),
                                              0.06 * kAlongGrainPa, 0.35, 2.5e6, 250.0,
                                              "across the grain: Wood Handbook FPL-GTR-190 tables 5-1, 5-2, 5-3 (E_T, nu, tension); "
                                              "Stanzl-Tschegg et al. 1995 (Gf)"),
                               7.9e6, 0.0, StrengthRateLaw::None, "Wood Handbook table 5-3b, Sitka spruce shear parallel to grain; no friction"),
                     GrainAxis::Z, kAlongGrainPa, 0.0625 * kAlongGrainPa, 70e6, 10e3, 3.0 * 7.9e6,
                     "along the grain: Wood Handbook tables 5-1 (E_L, G_LT) and 5-3a (modulus of rupture as tensile strength); "
                     "Ashby & Jones table 13.1 (Gf across the fibres); Kollmann & Cote 1968 (shear across the fibres)"),
                       0.005, "half the flexural loss factor of wood, about 10^-2 (Cremer & Heckl 1988)");
    const Material scattered = withScatter(wood, 0.25, 0.48,
                                           "strength CoV 0.25 (Wood Handbook table 5-6, tension parallel; JCSS PMC 3.5 across), correlated over 0.48 m "
                                           "(JCSS PMC 3.5 after Isaksson 1999: weak sections along a board)");
    // Weathered spruce outside, paler fresh wood where it splits.
    return withLook(withCrushing(scattered, 4.0e6, kCrushingDuctilityM * 4.0e6,
                        "Wood Handbook table 5-3a, Sitka spruce at 12 % moisture: 4.0 MPa across the grain, 38.7 MPa along it; "
                        "Gc from masonry's ductility index 1.6 mm (Lourenco 2008; no value for wood found)",
                        38.7e6, kCrushingDuctilityM * 38.7e6),
                    {0.40, 0.24, 0.10}, {0.69, 0.45, 0.21}, {0.69, 0.45, 0.21}, 0.7);
}

/// Bricks in mortar. The joints (the material's own values): E = 1000 fk with fk 5 MPa (EN
/// 1996-1-1 3.7.2), unit–mortar bond 0.3 MPa and mode I Gf 12 J/m² (van der Pluijm's tests as
/// quoted by Lourenco 1996, "Computational strategies for masonry structures", ch. 3: 0.3–0.9 MPa
/// and 5–20 J/m²), shear EN 1996-1-1 table 3.4 (clay units, general-purpose mortar M10–M20)
/// fvko = 0.3 MPa and eq. 3.5, fvk = fvko + 0.4 σd. The units: 215 × 102.5 × 65 mm (the UK work
/// size) in 10 mm joints, running bond, cracking at 2.0 MPa with 80 J/m² (Lourenço & Rots 1997,
/// J. Eng. Mech. 123(7), the potential cracks in the units of the TU Eindhoven shear walls).
/// No crushing (compressive_strength_Pa 0): with its fk, 5 MPa, the house wall of issue 47
/// carrying its floors collapses where it stands without (docs/accuracy.md, "Crushing"); a scene
/// may set it (docs/materials.md gives fk and Gc = 1.6 mm × fk, Lourenço 2008). Scatter (JCSS
/// Probabilistic Model Code, part 3 "Masonry", lognormal): the joints' CoV 0.30, the code's for
/// flexural tensile strength parallel to the bed joints (35 % across them, 40 % for cohesion);
/// the units' 0.24, its clay bricks' tensile strength; correlated over a course (65 mm), as a
/// wall's joints are nearly independent of each other (a modelling choice).
Material brickMasonryPreset()
{
    // Red clay brick, its broken interior a paler orange, grey cement mortar in the joints.
    return withLook(withScatter(withDamping(withUnits(withShear(withElasticity(calibrateMaterial("brick-masonry", 1900.0, 48.2e3, 55.1e3,
                                                                "Clancey 1972: unreinforced brick panels 8-12 in fail at 48.2-55.1 kPa"),
                                              5e9, 0.2, 0.3e6, 12.0, "EN 1996-1-1 (E = 1000 fk); van der Pluijm via Lourenco 1996 (bond strength, Gf)"),
                               0.3e6, 0.4, StrengthRateLaw::None, "EN 1996-1-1 table 3.4 and eq. 3.5 (fvko 0.3 MPa, 0.4 sigma_d)"),
                     0.215, 0.1025, 0.065, 0.01, 2.0e6, 80.0,
                     "215 x 102.5 x 65 mm bricks, 10 mm joints, running bond; potential cracks in units ft 2.0 MPa, Gf 80 J/m^2 "
                     "(Lourenco & Rots 1997, TU Eindhoven shear walls)"),
                       0.03, "ENV 1998-6:2003 Annex B, brickwork 3-10 % (the lower end: joints and cracks are resolved)"),
                    0.30, 0.065, "strength CoV 0.30 in joints, 0.24 in units (JCSS PMC part 3, masonry), correlated over a course (65 mm)", 0.24),
                    {0.45, 0.09, 0.047}, {0.54, 0.17, 0.08}, {0.48, 0.45, 0.38}, 0.9);
}

/// Concrete C30/37 with the given density and failure range: fib Model Code 2010 5.1: Eci =
/// 21.5 GPa (fcm/10)^(1/3) = 33.6 GPa, fctm = 0.3 fck^(2/3) = 2.9 MPa, Gf = 73 fcm^0.18 =
/// 141 J/m² (fcm = 38 MPa); Mohr–Coulomb through fcm and fctm (mohrCoulombThrough), strength
/// rising with strain rate as MC2010 5.1.11 gives for tension. Scatter: EN 1992-1-1 table 3.1
/// (and MC2010 5.1.5.1) put the 5 % fractile of the tensile strength at 0.7 fctm, so a normal
/// scatter's CoV is 0.3 / 1.645 = 0.18; its correlation length is the maximum aggregate size of
/// a common C30/37 mix, 16 mm (issue 18: "near its aggregate size"; a modelling choice, not a
/// measured length). Crushing at fcm with Gc = 250 Gf, the ratio the Dutch guidelines for
/// nonlinear finite element analysis of concrete recommend (Rijkswaterstaat RTD 1016-1:2017,
/// Hendriks et al.).
Material c30ConcretePreset(const std::string& name, double densityKgM3, double failureLowPa, double failureHighPa,
                           const std::string& failureSource, const std::string& elasticityNote)
{
    const auto [cohesionPa, friction] = mohrCoulombThrough(38e6, 2.9e6);
    const Material concrete = withDamping(withScatter(withShear(withElasticity(calibrateMaterial(name, densityKgM3, failureLowPa, failureHighPa, failureSource), 33.6e9, 0.2,
                                                2.9e6, 141.0, "fib Model Code 2010, C30/37: E 33.6 GPa, fctm 2.9 MPa, Gf 141 J/m^2" + elasticityNote),
                                 cohesionPa, friction, StrengthRateLaw::FibModelCode2010,
                                 "Mohr-Coulomb through fcm 38 MPa and fctm (Jaeger, Cook & Zimmerman 2007); rate: fib MC2010 5.1.11"),
                       0.3 / 1.645, 0.016,
                       "strength CoV 0.18 from EN 1992-1-1 table 3.1 (fctk,0.05 = 0.7 fctm), correlated over 16 mm (maximum aggregate size)"),
                       0.02, "ENV 1998-6:2003 Annex B, concrete elements 2-7 % (the lower end: cracks are resolved)");
    // Grey cast concrete; a crack shows the darker, rougher aggregate.
    return withLook(withCrushing(concrete, 38e6, 250.0 * 141.0, "fcm 38 MPa (fib MC2010, C30/37); Gc = 250 Gf (Rijkswaterstaat RTD 1016-1:2017)"),
                    {0.34, 0.34, 0.32}, {0.24, 0.23, 0.20}, {0.24, 0.23, 0.20}, 0.95);
}

/// Reinforced concrete: the same concrete (its steel is not modelled). Its failure range's high
/// end is NUKEMAP's heavy-damage benchmark (A. Wellerstein, nuclearsecrecy.com/nukemap): at
/// 20 psi = 137.9 kPa "heavily built concrete buildings are severely damaged or demolished"; its
/// low end keeps brick's relative spread (48.2/55.1).
Material reinforcedConcretePreset()
{
    return c30ConcretePreset("reinforced-concrete", 2500.0, 137.9e3 * (48.2 / 55.1), 137.9e3,
                             "NUKEMAP 20 psi benchmark: heavily built concrete buildings severely damaged or demolished at 137.9 kPa; "
                             "low end at brick's relative spread (120.6 kPa)",
                             " (steel not modelled)");
}

}  // namespace

const std::vector<Material>& materialPresets()
{
    static const std::vector<Material> presets = {
        glassPreset(), woodPreset(), brickMasonryPreset(),
        c30ConcretePreset("concrete", 2400.0, 13.8e3, 20.7e3, "Clancey 1972: unreinforced concrete/cinder block walls shatter at 13.8-20.7 kPa", ""),
        reinforcedConcretePreset(),
    };
    return presets;
}

const Material& findMaterialPreset(const std::string& name)
{
    std::string known;
    for (const Material& m : materialPresets()) {
        if (m.name == name) return m;
        known += (known.empty() ? "" : ", ") + m.name;
    }
    throw InputError("material '" + name + "' is unknown (presets: " + known + ")");
}

template <>
const std::vector<Field<Material>>& fieldTable<Material>()
{
    static const std::vector<Field<Material>> table = {
        {"density_kg_m3", &Material::densityKgM3, aboveZeroUpTo(1e12)},
        {"mean_yield_Pa", &Material::meanYieldPa, aboveZeroUpTo(1e12)},
        {"yield_variation", &Material::yieldVariation, fraction()},
        {"weakening_fraction", &Material::weakeningFraction, fraction()},
        {"orientation_factor", &Material::orientationFactor, fraction()},
        {"damage_rate_per_s", &Material::damageRatePerS, closed(0, 1e12)},
        {"damage_stress_scale_per_Pa", &Material::damageStressScalePerPa, closed(0, 1e12)},
        {"youngs_modulus_Pa", &Material::youngsModulusPa, aboveZeroUpTo(1e13)},
        {"poisson_ratio", &Material::poissonRatio, closed(0.0, 0.45)},
        {"tensile_strength_Pa", &Material::tensileStrengthPa, aboveZeroUpTo(1e11)},
        {"fracture_energy_J_per_m2", &Material::fractureEnergyJPerM2, aboveZeroUpTo(1e7)},
        {"shear_strength_Pa", &Material::shearStrengthPa, aboveZeroUpTo(1e11)},
        {"friction_coefficient", &Material::frictionCoefficient, closed(0.0, 10.0)},
        {"compressive_strength_Pa", &Material::compressiveStrengthPa, closed(0.0, 1e11)},
        {"compressive_fracture_energy_J_per_m2", &Material::compressiveFractureEnergyJPerM2, closed(0.0, 1e8)},
        {"strength_rate_law", choice(&Material::strengthRateLaw)},
        {"strength_cov", &Material::strengthCoefficientOfVariation, closed(0.0, 1.0)},
        {"strength_correlation_length_m", &Material::strengthCorrelationLengthM, aboveZeroUpTo(100.0)},
        {"unit_strength_cov", &Material::unitStrengthCoefficientOfVariation, closed(0.0, 1.0)},
        {"strength_distribution", choice(&Material::strengthDistribution)},
        {"strength_weibull_modulus", &Material::strengthWeibullModulus, closed(0.0, 100.0)},
        {"strength_reference_area_m2", &Material::strengthReferenceAreaM2, aboveZeroUpTo(1e6)},
        {"damping_ratio", &Material::dampingRatio, closed(0.0, 0.3)},
        {"unit_length_m", &Material::unitLengthM, closed(0.0, 100.0)},
        {"unit_width_m", &Material::unitWidthM, closed(0.0, 100.0)},
        {"unit_height_m", &Material::unitHeightM, closed(0.0, 100.0)},
        {"joint_thickness_m", &Material::jointThicknessM, closed(0.0, 1.0)},
        {"unit_length_axis", choice(&Material::unitLengthAxis)},
        {"unit_bond_pattern", choice(&Material::bondPattern)},
        {"unit_tensile_strength_Pa", &Material::unitTensileStrengthPa, closed(0.0, 1e11)},
        {"unit_fracture_energy_J_per_m2", &Material::unitFractureEnergyJPerM2, closed(0.0, 1e7)},
        {"unit_shear_strength_Pa", &Material::unitShearStrengthPa, closed(0.0, 1e11)},
        {"unit_friction_coefficient", &Material::unitFrictionCoefficient, closed(0.0, 10.0)},
        {"grain_axis", choice(&Material::grainAxis)},
        {"along_grain_youngs_modulus_Pa", &Material::alongGrainYoungsModulusPa, closed(0.0, 1e13)},
        {"along_grain_shear_modulus_Pa", &Material::alongGrainShearModulusPa, closed(0.0, 1e13)},
        {"along_grain_tensile_strength_Pa", &Material::alongGrainTensileStrengthPa, closed(0.0, 1e11)},
        {"along_grain_fracture_energy_J_per_m2", &Material::alongGrainFractureEnergyJPerM2, closed(0.0, 1e7)},
        {"along_grain_shear_strength_Pa", &Material::alongGrainShearStrengthPa, closed(0.0, 1e11)},
        {"along_grain_compressive_strength_Pa", &Material::alongGrainCompressiveStrengthPa, closed(0.0, 1e11)},
        {"along_grain_compressive_fracture_energy_J_per_m2", &Material::alongGrainCompressiveFractureEnergyJPerM2, closed(0.0, 1e8)},
        {"colour_rgb", &Material::colourRgb, closed(0.0, 1.0)},
        {"interior_colour_rgb", &Material::interiorColourRgb, closed(0.0, 1.0)},
        {"joint_colour_rgb", &Material::jointColourRgb, closed(0.0, 1.0)},
        {"roughness", &Material::roughness, closed(0.0, 1.0)},
        {"transmission", &Material::transmission, closed(0.0, 1.0)},
    };
    return table;
}

namespace {

/// What the lattice's calibration along a grain needs (calibrateLattice, lattice/LatticeBuild.cpp,
/// by Sherman–Morrison): across the grain d = E / (1 + ν) and κ = ν d / (1 + ν); the normal
/// modulus along it is the larger root of d_L² − E_L d_L + E_L κ, real when E_L ≥ 4κ; the
/// volumetric modulus κ / (1 − κ (1/d_L + 2/d)) needs a positive denominator. Any positive G_L
/// will do: each plane's shear springs are its own (2 h G).
FieldProblem grainCalibrationProblem(const Material& m)
{
    const double across = m.youngsModulusPa / (1.0 + m.poissonRatio), kappa = m.poissonRatio * across / (1.0 + m.poissonRatio);
    const double eAlong = m.alongGrainYoungsModulusPa, discriminant = eAlong * eAlong - 4.0 * eAlong * kappa;
    if (discriminant < 0.0)
        return {"along_grain_youngs_modulus_Pa", "must be at least 4 nu E / (1 + nu)^2 = " + std::to_string(4.0 * kappa) +
                                                     " Pa with youngs_modulus_Pa and poisson_ratio across the grain (no lattice has a smaller one)"};
    const double along = 0.5 * (eAlong + std::sqrt(discriminant));
    if (!(1.0 - kappa * (1.0 / along + 2.0 / across) > 0.0))
        return {"along_grain_youngs_modulus_Pa", "is too small against youngs_modulus_Pa and poisson_ratio across the grain (the lattice's "
                                                 "volumetric modulus would not be positive)"};
    return {};
}

/// A material that crushes needs the energy crushing takes, and with a grain, both along it.
FieldProblem crushingProblem(const Material& m)
{
    if (!(m.compressiveStrengthPa > 0.0)) return {};
    const char* reason = "must be above 0 when compressive_strength_Pa is (crushing dissipates energy; compressive_strength_Pa 0 never crushes)";
    if (!(m.compressiveFractureEnergyJPerM2 > 0.0)) return {"compressive_fracture_energy_J_per_m2", reason};
    if (!hasGrain(m)) return {};
    if (!(m.alongGrainCompressiveStrengthPa > 0.0)) return {"along_grain_compressive_strength_Pa", reason};
    if (!(m.alongGrainCompressiveFractureEnergyJPerM2 > 0.0)) return {"along_grain_compressive_fracture_energy_J_per_m2", reason};
    return {};
}

/// A Weibull scatter needs its modulus.
FieldProblem scatterProblem(const Material& m)
{
    if (m.strengthDistribution == StrengthDistribution::Weibull && !(m.strengthWeibullModulus > 0.0))
        return {"strength_weibull_modulus", "must be above 0 when strength_distribution is weibull (glass: 7, ASTM E1300)"};
    return {};
}

}  // namespace

FieldProblem structureProblem(const Material& m)
{
    if (const FieldProblem problem = scatterProblem(m); !problem.key.empty()) return problem;
    if (hasUnits(m) && hasGrain(m)) return {"grain_axis", "must be none for a material built of units (unit_length_m above 0)"};
    std::vector<std::pair<const char*, double>> needed;
    std::string reason;
    if (hasUnits(m)) {
        needed = {{"unit_width_m", m.unitWidthM},
                  {"unit_height_m", m.unitHeightM},
                  {"unit_tensile_strength_Pa", m.unitTensileStrengthPa},
                  {"unit_fracture_energy_J_per_m2", m.unitFractureEnergyJPerM2},
                  {"unit_shear_strength_Pa", m.unitShearStrengthPa}};
        reason = "must be above 0 when unit_length_m is (a material built of units; unit_length_m 0 makes it homogeneous)";
    } else if (hasGrain(m)) {
        needed = {{"along_grain_youngs_modulus_Pa", m.alongGrainYoungsModulusPa},
                  {"along_grain_shear_modulus_Pa", m.alongGrainShearModulusPa},
                  {"along_grain_tensile_strength_Pa", m.alongGrainTensileStrengthPa},
                  {"along_grain_fracture_energy_J_per_m2", m.alongGrainFractureEnergyJPerM2},
                  {"along_grain_shear_strength_Pa", m.alongGrainShearStrengthPa}};
        reason = "must be above 0 when grain_axis is set (grain_axis none makes the material the same in every direction)";
    }
    for (const auto& [key, value] : needed)
        if (!(value > 0.0)) return {key, reason};
    if (const FieldProblem problem = crushingProblem(m); !problem.key.empty()) return problem;
    if (hasGrain(m)) return grainCalibrationProblem(m);
    return {};
}

void validateMaterial(const Material& m)
{
    validateFields(m, "material '" + m.name + "'");
    if (const FieldProblem problem = structureProblem(m); !problem.key.empty())
        throw InputError("material '" + m.name + "': " + problem.key + " " + problem.reason);
}

double pWaveSpeedMS(const Material& m)
{
    const double nu = m.poissonRatio;
    return std::sqrt(m.youngsModulusPa * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu) * m.densityKgM3));
}

double crackingImpactSpeedMS(const Material& m) { return 0.125 * m.tensileStrengthPa / (m.densityKgM3 * pWaveSpeedMS(m)); }

double acrossCoursesStrengthRatio(const Material& m)
{
    const double courseM = m.unitHeightM + m.jointThicknessM, lengthPitchM = m.unitLengthM + m.jointThicknessM;
    // The units' overlap from course to course: half a unit in running bond, a quarter in
    // English and Flemish bonds (masonryUnitOf's layouts).
    const double overlapM = m.bondPattern == BondPattern::Running ? 0.5 * lengthPitchM : 0.25 * lengthPitchM;
    // Per course: a head joint in tension over the unit's height and a bed joint sliding over
    // the overlap (cohesion alone: no precompression assumed) ...
    const double steppedPa = (m.tensileStrengthPa * m.unitHeightM + m.shearStrengthPa * overlapM) / courseM;
    // ... or, over two courses, a unit and a head joint in tension.
    const double straightPa = (m.unitTensileStrengthPa + m.tensileStrengthPa) * m.unitHeightM / (2.0 * courseM);
    return std::min(steppedPa, straightPa) / m.tensileStrengthPa;
}

bool acrossJoint(const Material& m, const Eigen::Vector3d& aM, const Eigen::Vector3d& bM)
{
    return hasUnits(m) && masonryUnitOf(m, aM.x(), aM.y(), aM.z()) != masonryUnitOf(m, bM.x(), bM.y(), bM.z());
}

std::array<int64_t, 3> masonryUnitOf(const Material& m, double xM, double yM, double zM)
{
    // A point exactly on a joint (common: voxel centres fall on it when h divides the pitch)
    // goes to the unit above it whatever the rounding of its coordinate.
    const auto index = [](double coordinateM, double pitchM) { return int64_t(std::floor(coordinateM / pitchM + 1e-9)); };
    const double alongM = m.unitLengthAxis == UnitLengthAxis::X ? xM : yM, acrossM = m.unitLengthAxis == UnitLengthAxis::X ? yM : xM;
    const double lengthPitchM = m.unitLengthM + m.jointThicknessM, widthPitchM = m.unitWidthM + m.jointThicknessM;
    const int64_t course = index(zM, m.unitHeightM + m.jointThicknessM);
    const bool odd = (course & 1) != 0;
    // Keys: a stretcher's (along, across, course); a header's first key is offset so that it
    // differs from every stretcher's in its course.
    switch (m.bondPattern) {
    case BondPattern::Running:
        return {index(alongM + (odd ? 0.5 * lengthPitchM : 0.0), lengthPitchM), index(acrossM, widthPitchM), course};
    case BondPattern::English:
        // Header courses: units across the wall, their joints a quarter unit off the stretchers'
        // (the queen closer at the end of each header course).
        if (!odd) return {index(alongM, lengthPitchM), index(acrossM, widthPitchM), course};
        return {index(alongM + 0.25 * lengthPitchM, widthPitchM), index(acrossM, lengthPitchM), course};
    case BondPattern::Flemish: {
        // Stretcher then header along each course; the next course shifted half the period, so
        // each header sits centred on a stretcher.
        const double periodM = lengthPitchM + widthPitchM, shiftedM = alongM + (odd ? 0.5 * periodM : 0.0);
        const int64_t period = index(shiftedM, periodM);
        const bool header = shiftedM - double(period) * periodM >= lengthPitchM - 1e-9 * periodM;
        return header ? std::array<int64_t, 3>{2 * period + 1, index(acrossM, lengthPitchM), course}
                      : std::array<int64_t, 3>{2 * period, index(acrossM, widthPitchM), course};
    }
    }
    return {0, 0, course};
}

}  // namespace spall
