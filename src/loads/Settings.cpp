#include <spall/loads/Settings.h>

namespace spall {

template <>
const std::vector<Field<LoadSettings>>& fieldTable<LoadSettings>()
{
    static const std::vector<Field<LoadSettings>> table = {
        {"solver.reflected_pressure", &LoadSettings::reflectedPressure},
    };
    return table;
}

}  // namespace spall
