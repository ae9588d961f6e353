// Integer arithmetic on voxel and sample indices, which run negative as well as positive.
#pragma once

namespace spall {

/// floor(value / divisor) for divisor > 0 (C++'s / rounds toward zero).
inline int floorDivide(int value, int divisor) { return value >= 0 ? value / divisor : -((-value + divisor - 1) / divisor); }

}  // namespace spall
