// Settings of the fracture stage (the paper's rules, section 3.3). Plain structs with defaults
// and a unit on every field.
#pragma once

#include <spall/core/EnumNames.h>
#include <spall/core/Fields.h>

#include <cstdint>

namespace spall {

enum class FractureAlgorithm {
    YieldLimit,      ///< variable limit (1), with weakening (2) and orientation (3) as switched
    DavisonStevens,  ///< damage accumulation (4)
    None,            ///< unbreakable
    /// From stress: the deformable phase (lattice/), bonds with the material's E, ν, tensile
    /// strength and fracture energy, while the blast loads a body and it vibrates.
    Lattice,
};
template <>
struct EnumNames<FractureAlgorithm> {
    static constexpr std::pair<FractureAlgorithm, const char*> kNames[] = {{FractureAlgorithm::YieldLimit, "yield-limit"},
                                                                           {FractureAlgorithm::DavisonStevens, "davison-stevens"},
                                                                           {FractureAlgorithm::None, "none"},
                                                                           {FractureAlgorithm::Lattice, "lattice"}};
};

/// What happens to parts smaller than the minimum fragment size.
enum class SmallFragmentPolicy { Keep, Dust };
template <>
struct EnumNames<SmallFragmentPolicy> {
    static constexpr std::pair<SmallFragmentPolicy, const char*> kNames[] = {{SmallFragmentPolicy::Keep, "keep"},
                                                                             {SmallFragmentPolicy::Dust, "dust"}};
};

struct FractureSettings {
    FractureAlgorithm algorithm = FractureAlgorithm::Lattice;  ///< from stress; the paper's rules are baselines
    bool weakening = true;    ///< algorithm 2 on top of 1
    bool orientation = true;  ///< algorithm 3 on top of 1
    int64_t minFragmentVoxels = 1;  ///< smaller pieces follow smallFragments (unit: voxels)
    SmallFragmentPolicy smallFragments = SmallFragmentPolicy::Keep;
};

// Keys and ranges (src/fracture/Settings.cpp).
template <>
const std::vector<Field<FractureSettings>>& fieldTable<FractureSettings>();

}  // namespace spall
