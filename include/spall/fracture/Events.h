// What fracture leaves behind for the history: splits and dust (data only).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace spall {

/// One split: a parent body replaced by its parts.
struct FractureEvent {
    double timeS = 0;
    int64_t parentId = -1;
    std::vector<int64_t> childIds;
};

/// A piece removed as dust (smaller than the minimum fragment size), with what it carried.
struct DustRecord {
    double timeS = 0;
    int64_t parentId = -1;
    int64_t voxelCount = 0;
    double massKg = 0;
    Eigen::Vector3d linearMomentum = Eigen::Vector3d::Zero();
    Eigen::Vector3d angularMomentumAboutOrigin = Eigen::Vector3d::Zero();
};

}  // namespace spall
