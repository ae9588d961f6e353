#include <spall/blast/Settings.h>

namespace spall {

template <>
const std::vector<Field<Atmosphere>>& fieldTable<Atmosphere>()
{
    static const std::vector<Field<Atmosphere>> table = {
        {"atmosphere.pressure_Pa", &Atmosphere::pressurePa, aboveZeroUpTo(1e8)},
        {"atmosphere.temperature_K", &Atmosphere::temperatureK, aboveZeroUpTo(1e4)},
    };
    return table;
}

template <>
const std::vector<Field<Charge>>& fieldTable<Charge>()
{
    static const std::vector<Field<Charge>> table = {
        {"position_m", &Charge::positionM},
        {"tnt_kg", &Charge::tntKg, aboveZeroUpTo(1e9)},
        {"detonation_time_s", &Charge::detonationTimeS, closed(0, 1e5)},
        {"burst", choice(&Charge::burst)},
    };
    return table;
}

template <>
const std::vector<Field<BlastSettings>>& fieldTable<BlastSettings>()
{
    static const std::vector<Field<BlastSettings>> table = {
        {"blast.dataset", choice(&BlastSettings::dataset)},
        {"blast.table_nodes_per_decade", &BlastSettings::tableNodesPerDecade, closed(2, 100000)},
    };
    return table;
}

std::vector<Charge> withGroundImages(const std::vector<Charge>& charges, const Eigen::Vector3d& groundNormal, double groundHeightM)
{
    std::vector<Charge> all = charges;
    const Eigen::Vector3d n = groundNormal.normalized();
    for (const Charge& c : charges) {
        const double height = n.dot(c.positionM) - groundHeightM;
        if (c.burst != BurstType::FreeAir || !(height > 0.0)) continue;
        Charge image = c;
        image.positionM = c.positionM - 2.0 * height * n;
        all.push_back(image);
    }
    return all;
}

}  // namespace spall
