// The solve and correct phases: sequential impulses over one step's contacts (restitution,
// Coulomb friction; accumulated normal impulses stay non-negative), then position correction.
#pragma once

#include <spall/dynamics/Contacts.h>
#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>

#include <cstdint>
#include <utility>
#include <vector>

namespace spall {

/// The last step's contact points with their normal and friction impulses, keyed by the pair
/// of body ids (or body id and -2 - static collider); the next step's solver starts each new
/// point from the old point nearest to it in the first body's frame (warm starting), so a stack
/// holds its weight and a body on a slope its grip from the first iteration.
struct ContactCache {
    struct Point {
        std::pair<int64_t, int64_t> key;
        Eigen::Vector3d localM;  ///< in the first body's frame, relative to its centre of mass (unit: m)
        double normalNs = 0;     ///< (unit: N s)
        Eigen::Vector3d frictionNs = Eigen::Vector3d::Zero();  ///< (unit: N s)
    };
    /// Sorted by key (a flat list: rebuilding a hash map of lists every step cost a tenth of a
    /// step in a large pile).
    std::vector<Point> points;
};

/// Solves the contacts together and writes the new velocities of the bodies that take impulses
/// (takesContactImpulses: a free body in the deformable phase as a rigid body, whose lattice
/// the caller hands the change); `cache` warm starts the solve and keeps its impulses for the
/// next step. Deterministic.
void solveContacts(std::vector<Body>& bodies, const ContactSet& contacts, const WorldSettings& world,
                   const CollisionSettings& collisions, double dtS, ContactCache& cache);

/// Removes a fifth of the penetration beyond a hundredth of a voxel and the bodies' overlap slack
/// per step by moving positions only (velocities untouched: no kinetic energy is added), then
/// shrinks each body's slack to what it still overlaps. Constraints: per body and static collider
/// its deepest contact, per touching pair its manifold, split by inverse mass; a few Gauss–Seidel
/// passes from the bottom up, each seeing the depth that earlier moves left.
void correctPositions(std::vector<Body>& bodies, const ContactSet& contacts, const WorldSettings& world);

}  // namespace spall
