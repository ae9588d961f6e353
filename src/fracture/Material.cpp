#include <spall/fracture/Material.h>

#include <spall/core/Error.h>

#include <cmath>

namespace spall {

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

const std::vector<Material>& materialPresets()
{
    // Failure overpressures: Clancey (1972), "Monitoring dangerous explosions", damage table as
    // quoted widely (e.g. explosion-safety.jp "Damage from Blast (Clancey)"):
    //   glass windows, large and small, usually shattered     3.4–6.9 kPa
    //   wood panels (standard housing) fail, blow in           6.9–13.8 kPa
    //   concrete or cinder block walls, not reinforced, shatter 13.8–20.7 kPa
    //   brick panels 8–12 in thick, not reinforced, fail        48.2–55.1 kPa
    // Reinforced concrete has no entry there. Its high end is NUKEMAP's heavy-damage benchmark
    // (A. Wellerstein, nuclearsecrecy.com/nukemap): at 20 psi = 137.9 kPa "heavily built concrete
    // buildings are severely damaged or demolished"; its low end keeps brick's relative spread
    // (48.2/55.1). Densities: typical values; concrete and reinforced concrete from
    // EN 1991-1-1 Table A.1 (24 and 25 kN/m^3).
    static const std::vector<Material> presets = {
        calibrateMaterial("glass", 2500.0, 3.4e3, 6.9e3, "Clancey 1972: windows shatter at 3.4-6.9 kPa"),
        calibrateMaterial("wood", 500.0, 6.9e3, 13.8e3, "Clancey 1972: wood panels fail at 6.9-13.8 kPa"),
        calibrateMaterial("brick-masonry", 1900.0, 48.2e3, 55.1e3,
                          "Clancey 1972: unreinforced brick panels 8-12 in fail at 48.2-55.1 kPa"),
        calibrateMaterial("concrete", 2400.0, 13.8e3, 20.7e3,
                          "Clancey 1972: unreinforced concrete/cinder block walls shatter at 13.8-20.7 kPa"),
        calibrateMaterial("reinforced-concrete", 2500.0, 137.9e3 * (48.2 / 55.1), 137.9e3,
                          "NUKEMAP 20 psi benchmark: heavily built concrete buildings severely damaged or demolished at "
                          "137.9 kPa; low end at brick's relative spread (120.6 kPa)"),
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
    };
    return table;
}

void validateMaterial(const Material& m) { validateFields(m, "material '" + m.name + "'"); }

}  // namespace spall
