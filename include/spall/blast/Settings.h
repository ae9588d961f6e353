// Settings of the blast stage: the charges, the reference dataset and the atmosphere.
// Plain structs with defaults and a unit on every field.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>

#include <Eigen/Core>

#include <cmath>

namespace spall {

enum class BurstType { FreeAir, Surface };
template <>
struct EnumNames<BurstType> {
    static constexpr std::pair<BurstType, const char*> kNames[] = {{BurstType::FreeAir, "free-air"}, {BurstType::Surface, "surface"}};
};

enum class BlastDataset { KingeryBulmash, KinneyGraham };
template <>
struct EnumNames<BlastDataset> {
    static constexpr std::pair<BlastDataset, const char*> kNames[] = {{BlastDataset::KingeryBulmash, "kingery-bulmash"},
                                                                      {BlastDataset::KinneyGraham, "kinney-graham"}};
};

struct Atmosphere {
    double pressurePa = 101325.0;   ///< ambient pressure (unit: Pa)
    double temperatureK = 288.15;   ///< ambient temperature (unit: K)
};

struct Charge {
    Eigen::Vector3d positionM = Eigen::Vector3d::Zero();  ///< (unit: m)
    double tntKg = 1.0;             ///< TNT-equivalent mass (unit: kg)
    double detonationTimeS = 0.0;   ///< (unit: s)
    BurstType burst = BurstType::Surface;
};

/// Height above the ground (unit: m) within which a charge of `tntKg` is a surface burst: two
/// radii of a TNT sphere of density 1600 kg/m^3 (cast TNT), i.e. it rests on or almost on the
/// ground, where the Kingery–Bulmash hemispherical data apply.
inline double surfaceBurstHeightM(double tntKg) { return 2.0 * std::cbrt(3.0 * tntKg / (4.0 * M_PI * 1600.0)); }

/// The charges with the ground's reflection: each free-air charge above the ground gets an image,
/// its mirror through the ground plane (normal . x = heightM), of the same mass and time. The
/// image's wave is the wave the ground reflects, superposed linearly on the direct one (exact
/// for weak waves; docs/accuracy.md for where the two merge). Surface bursts already carry the
/// ground in their hemispherical data.
std::vector<Charge> withGroundImages(const std::vector<Charge>& charges, const Eigen::Vector3d& groundNormal, double groundHeightM);

struct BlastSettings {
    BlastDataset dataset = BlastDataset::KingeryBulmash;
    /// Table nodes per decade of scaled distance; see docs/accuracy.md for the error it buys
    /// (unit: nodes per decade).
    int tableNodesPerDecade = 128;
    Atmosphere atmosphere;
};

// Keys and ranges (src/blast/Settings.cpp).
template <>
const std::vector<Field<Atmosphere>>& fieldTable<Atmosphere>();
template <>
const std::vector<Field<Charge>>& fieldTable<Charge>();
template <>
const std::vector<Field<BlastSettings>>& fieldTable<BlastSettings>();

}  // namespace spall
