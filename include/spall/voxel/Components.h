// Connected components over intact links (paper section 3.3): the bodies after fracture.
#pragma once

#include <spall/voxel/Body.h>

#include <cstdint>
#include <vector>

namespace spall {

/// Component label of every voxel slot, indexed leafIndex * 512 + offset in leaf order.
/// Label k is the k-th component met in leaf order, so labels do not depend on thread count.
struct ComponentLabels {
    std::vector<const LinkLeaf*> leaves;
    std::vector<uint32_t> labelOfSlot;  ///< kNoLabel for inactive slots
    uint32_t componentCount = 0;
    static constexpr uint32_t kNoLabel = 0xffffffffu;
};

ComponentLabels labelComponents(const LinkGrid& grid);

/// One grid per component, same index space and transform as the input, values copied.
std::vector<LinkGrid::Ptr> splitByLabels(const LinkGrid& grid, const ComponentLabels& labels);

}  // namespace spall
