#include <spall/loads/Settings.h>

namespace spall {

const std::vector<Field<LoadSettings>>& FieldTable<LoadSettings>::fields()
{
    static const std::vector<Field<LoadSettings>> table = {
        {"solver.reflected_pressure", &LoadSettings::reflectedPressure},
    };
    return table;
}

}  // namespace spall
