// Sleep and wake: every rule that puts a body to rest or wakes it lives here. A sleeping body is
// static for the solver until the blast reaches it or a moving body hits it.
#pragma once

#include <spall/dynamics/BroadPhase.h>
#include <spall/dynamics/NarrowPhase.h>
#include <spall/dynamics/Settings.h>
#include <spall/voxel/Body.h>

#include <vector>

namespace spall {

/// Wakes the bodies the blast loads this step (`loaded` per body).
void wakeLoadedBodies(std::vector<Body>& bodies, const std::vector<char>& loaded);

/// A moving body (faster than the sleep speed) wakes a sleeping one it touches; a resting one
/// leaves it asleep.
void wakeBodiesHitByMovers(std::vector<Body>& bodies, const std::vector<ContactManifold>& manifolds, const SleepSettings& sleep);

/// Rest times per body (a loaded body does not rest), then islands of touching bodies (anchored
/// bodies join none) by union-find: an island sleeps when all its awake bodies have rested for
/// the sleep time. Sleeping body by body instead lets settling neighbours knock each other awake
/// again and again. Does nothing when sleep is off.
void updateSleep(std::vector<Body>& bodies, const std::vector<BodyPair>& touching, const std::vector<char>& loaded,
                 const SleepSettings& sleep, double dtS);

}  // namespace spall
