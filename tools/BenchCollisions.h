// `spall bench collisions`: the paper's Table 5-1 (steps per second against boundary voxels for
// no collision detection, pairwise tests, buckets) plus spall's tree lookup and, where built
// with it, Bullet on the same debris pile.
#pragma once

namespace spall {

/// Runs every method on a debris pile and an explosion at sizes from 10 to 10^6 boundary voxels;
/// prints a table with ratios (or one JSON row per method and size). `maxBoundaryVoxels` bounds
/// the sizes (CI uses a small value). Returns the exit code.
int benchCollisions(bool json, long maxBoundaryVoxels);

}  // namespace spall
