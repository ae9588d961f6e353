#include <spall/dynamics/StaticContacts.h>

#include <spall/dynamics/NarrowPhase.h>

#include "VoxelContact.h"

#include <algorithm>
#include <cmath>

namespace spall {

namespace {

using narrow::kContactMarginVoxels;

/// Whether the body's bounding sphere comes within `reachM` of the ground's plane or of the box.
bool groundWithinReach(const Body& body, const GroundPlane& ground, double reachM)
{
    return ground.enabled && ground.normal.dot(body.motion.positionM) - ground.offsetM <= body.boundingRadiusM + reachM;
}
bool boxWithinReach(const Body& body, const StaticBox& box, double reachM)
{
    const Eigen::Vector3d local = box.orientation.inverse() * (body.motion.positionM - box.centreM);
    const Eigen::Vector3d outside = (local.cwiseAbs() - box.halfExtentM).cwiseMax(0.0);
    return outside.norm() <= body.boundingRadiusM + reachM;
}

/// Corners of the body's boundary voxels inside the ground or a static box, into `contacts`
/// (emptied first).
void findCorners(const Body& body, const WorldSettings& world, std::vector<StaticContact>& contacts)
{
    contacts.clear();
    const Eigen::Matrix3d rot = body.motion.orientation.toRotationMatrix();
    const double h = body.voxelSizeM;
    const double margin = kContactMarginVoxels * h;
    const double voxelRadius = 0.5 * std::sqrt(3.0) * h + margin;
    const GroundPlane& ground = world.ground;
    const bool nearGround = groundWithinReach(body, ground, margin);
    std::vector<int> nearBoxes;
    for (size_t b = 0; b < world.colliders.size(); ++b)
        if (boxWithinReach(body, world.colliders[b], margin)) nearBoxes.push_back(static_cast<int>(b));
    if (!nearGround && nearBoxes.empty()) return;

    for (const openvdb::Coord& voxel : body.boundaryVoxels) {
        const Eigen::Vector3d centreArm = rot * body.voxelOffsetM(voxel);
        const Eigen::Vector3d centre = body.motion.positionM + centreArm;
        // Eight corners per voxel: a face resting on a collider gets four points, so resting
        // bodies do not pivot about a single point.
        auto corners = [&](auto&& visit) {
            for (int c = 0; c < 8; ++c)
                visit(0.5 * h * (rot.col(0) * (c & 1 ? 1 : -1) + rot.col(1) * (c & 2 ? 1 : -1) + rot.col(2) * (c & 4 ? 1 : -1)));
        };
        if (nearGround && ground.normal.dot(centre) - ground.offsetM < voxelRadius) {
            corners([&](const Eigen::Vector3d& corner) {
                const double separation = ground.normal.dot(centre + corner) - ground.offsetM;
                if (separation < margin)
                    contacts.push_back({centreArm + corner, ground.normal, -separation, -1, ground.restitution, ground.friction});
            });
        }
        for (int b : nearBoxes) {
            const StaticBox& box = world.colliders[b];
            const Eigen::Matrix3d boxRot = box.orientation.toRotationMatrix();
            const Eigen::Vector3d local = boxRot.transpose() * (centre - box.centreM);
            if (((local.cwiseAbs() - box.halfExtentM).array() > voxelRadius).any()) continue;
            corners([&](const Eigen::Vector3d& corner) {
                const Eigen::Vector3d q = boxRot.transpose() * (centre + corner - box.centreM);
                const Eigen::Vector3d penetration = box.halfExtentM - q.cwiseAbs();
                if ((penetration.array() <= -margin).any() || (penetration.array() <= 0.0).count() > 1) return;
                int axis = 0;
                penetration.minCoeff(&axis);
                const Eigen::Vector3d normal = boxRot.col(axis) * (q[axis] >= 0 ? 1.0 : -1.0);
                contacts.push_back({centreArm + corner, normal, penetration[axis], b, box.restitution, box.friction});
            });
        }
    }
}

/// Per collider and normal, the corners reduced to at most four spanning points and the
/// deepest. `done`, `group` and `points` are working space.
std::vector<StaticContact> reduceStaticContacts(const std::vector<StaticContact>& all, std::vector<char>& done, std::vector<size_t>& group,
                                                std::vector<VoxelContact>& points)
{
    std::vector<StaticContact> reduced;
    done.assign(all.size(), 0);
    for (size_t i = 0; i < all.size(); ++i) {
        if (done[i]) continue;
        group.clear();
        points.clear();
        size_t deepest = 0;
        for (size_t j = i; j < all.size(); ++j)
            if (!done[j] && all[j].collider == all[i].collider && all[j].normal == all[i].normal) {
                done[j] = 1;
                if (all[j].depth > all[group.empty() ? j : group[deepest]].depth) deepest = group.size();
                group.push_back(j);
                points.push_back({all[j].arm, all[j].normal, all[j].depth});
            }
        // The deepest too: the position correction works on each collider's deepest contact.
        std::vector<size_t> chosen = spanningPoints(points, all[i].normal);
        if (std::find(chosen.begin(), chosen.end(), deepest) == chosen.end()) chosen.push_back(deepest);
        for (size_t k : chosen) reduced.push_back(all[group[k]]);
    }
    return reduced;
}

}  // namespace

std::vector<StaticContact> findStaticContacts(const Body& body, const WorldSettings& world)
{
    // A slab lying on the ground has hundreds of thousands of corners on it: its working space
    // is kept per thread, so that a step neither allocates it nor faults its pages in afresh
    // (they were most of the flight of the 3 M-voxel wall's slabs, docs/performance.md).
    thread_local std::vector<StaticContact> corners;
    thread_local std::vector<char> done;
    thread_local std::vector<size_t> group;
    thread_local std::vector<VoxelContact> points;
    findCorners(body, world, corners);
    return reduceStaticContacts(corners, done, group, points);
}

bool withinReachOfStatics(const Body& body, const WorldSettings& world, double reachM)
{
    return groundWithinReach(body, world.ground, reachM) ||
           std::any_of(world.colliders.begin(), world.colliders.end(), [&](const StaticBox& box) { return boxWithinReach(body, box, reachM); });
}

double fastestClosingSpeedMS(const Body& body, const std::vector<StaticContact>& contacts, double groundShare)
{
    double fastestMS = 0.0;
    for (const StaticContact& c : contacts) {
        const double closingMS = -c.normal.dot(body.motion.linearVelocityMS + body.motion.angularVelocityRadS.cross(c.arm));
        fastestMS = std::max(fastestMS, c.collider < 0 ? groundShare * closingMS : closingMS);
    }
    return fastestMS;
}

}  // namespace spall
