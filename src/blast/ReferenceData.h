// What the blast stage's reference fits and the tables built from them share.
#pragma once

#include <spall/blast/Settings.h>

namespace spall::blastdata {

constexpr double kSeaLevelPressurePa = 101325.0;
constexpr double kSeaLevelTemperatureK = 288.15;
constexpr double kSoundSpeedMS = 340.29;  // sea level, 15 °C
constexpr double kNegativeDurationScaledS = 12.5e-3;  // Granström: T- = 12.5 ms W^(1/3)

/// The scaled distances a dataset's fits cover (unit: m/kg^(1/3)).
struct ZRange {
    double lo, hi;
};
ZRange fittedRange(BlastDataset dataset, BurstType burst);

/// Shock front speed of a shock of overpressure ps at ambient p0 (Rankine–Hugoniot, ideal gas;
/// blast-data.md §5) (unit: m/s).
double rankineHugoniotShockSpeed(double ps, double p0);

}  // namespace spall::blastdata
