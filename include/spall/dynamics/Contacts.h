// The detect phase: every contact of the bodies' current poses, with the ground, the static boxes
// and each other (paper section 4.2).
#pragma once

#include <spall/dynamics/BroadPhase.h>
#include <spall/dynamics/NarrowPhase.h>
#include <spall/dynamics/Settings.h>
#include <spall/dynamics/StaticContacts.h>
#include <spall/voxel/Body.h>

#include <cstdint>
#include <vector>

namespace spall {

/// One step's contacts, as the solver and the position correction take them.
struct ContactSet {
    std::vector<ContactManifold> manifolds;           ///< between bodies, sorted by pair
    std::vector<std::vector<StaticContact>> statics;  ///< per body (movable ones only)
    std::vector<BodyPair> touching;                   ///< pairs with contacts, sorted
    int64_t staticContacts = 0;   ///< reduced points on the ground and static boxes
    int64_t bodyContacts = 0;     ///< voxel pairs between bodies, before reduction
    int64_t solverContacts = 0;   ///< points the solver works on (static ones and the manifolds')
};

/// The speed along a contact's normal below which it rests rather than strikes: what gravity
/// adds in a couple of steps, plus a margin (unit: m/s).
double impactSpeedMS(const WorldSettings& world, double dtS);

/// The closing speed above which a contact's penetration is the step's doing: faster than one
/// that rests (impactSpeedMS) and fast enough to go a twentieth of a voxel deeper in a step. A
/// piece wedged in a notch of another jitters at a tenth of a metre per second, deep, and a
/// shorter step neither deepens nor frees it; with the first rule alone one such piece held
/// the 3 M-voxel wall's flight at 1/64 of its step (unit: m/s).
double tunnellingSpeedMS(const WorldSettings& world, double dtS, double voxelSizeM);

/// The fastest the two bodies of a manifold close on each other along its normal at one of
/// its points (unit: m/s; 0 when they part everywhere).
double fastestClosingSpeedMS(const std::vector<Body>& bodies, const ContactManifold& manifold);

/// The deepest contact between bodies that still close on each other faster than
/// `closingSpeedMS` at one of its points (unit: m; 0 when none): a penetration the step is
/// making, not one that rests (pieces born interlocked, which the position correction
/// separates and a shorter step would not).
double deepestClosingPenetrationM(const std::vector<Body>& bodies, const ContactSet& contacts, double closingSpeedMS);

/// Contacts between bodies, then wakes sleeping bodies a moving one hits (they take part in the
/// solve), then contacts of every movable body with the ground and the static boxes, and of a
/// free body in the deformable phase with the boxes (its lattice keeps itself above the ground).
/// Deterministic for any thread count.
ContactSet detectContacts(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                          const SleepSettings& sleep);

}  // namespace spall
