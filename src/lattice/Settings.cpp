#include <spall/lattice/Settings.h>

namespace spall {

template <>
const std::vector<Field<LatticeSettings>>& fieldTable<LatticeSettings>()
{
    static const std::vector<Field<LatticeSettings>> table = {
        {"lattice.bulk_viscosity", &LatticeSettings::bulkViscosity, closed(0.0, 1.0)},
        {"lattice.handoff_energy_fraction", &LatticeSettings::handoffEnergyFraction, closed(0.0, 1.0)},
        {"lattice.max_vibration_s", &LatticeSettings::maxVibrationS, closed(0.0, 10.0)},
        {"lattice.handoff_check_interval_s", &LatticeSettings::handoffCheckIntervalS, closed(1e-7, 1.0)},
        {"lattice.handoff_residual_strength", &LatticeSettings::handoffResidualStrength, closed(0.0, 1.0)},
        {"lattice.damage_law", choice(&LatticeSettings::damageLaw)},
        {"lattice.impact_fracture", &LatticeSettings::impactFracture},
        {"lattice.separate_during_blast", &LatticeSettings::separateDuringBlast},
        {"lattice.particle_voxels", &LatticeSettings::particleVoxels, closed(1, 8)},
    };
    return table;
}

}  // namespace spall
