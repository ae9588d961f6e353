#include <spall/fracture/Settings.h>

namespace spall {

template <>
const std::vector<Field<FractureSettings>>& fieldTable<FractureSettings>()
{
    // The seed is the scene's (a key of its own at the top).
    static const std::vector<Field<FractureSettings>> table = {
        {"fracture.algorithm", choice(&FractureSettings::algorithm)},
        {"fracture.weakening", &FractureSettings::weakening},
        {"fracture.orientation", &FractureSettings::orientation},
        {"fracture.min_fragment_voxels", &FractureSettings::minFragmentVoxels, atLeast(1)},
        {"fracture.small_fragments", choice(&FractureSettings::smallFragments)},
    };
    return table;
}

}  // namespace spall
