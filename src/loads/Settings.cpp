#include <spall/loads/Settings.h>

namespace spall {

template <>
const std::vector<Field<LoadSettings>>& fieldTable<LoadSettings>()
{
    static const std::vector<Field<LoadSettings>> table = {
        {"loads.model", choice(&LoadSettings::model)},
    };
    return table;
}

}  // namespace spall
