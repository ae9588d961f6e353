#include <spall/dynamics/Sleep.h>

#include <spall/core/DisjointSets.h>
#include <spall/dynamics/Integrate.h>

#include <algorithm>

namespace spall {

namespace {

void wake(Body& body)
{
    body.motion.asleep = false;
    body.motion.restTimeS = 0;
}

}  // namespace

void wakeLoadedBodies(std::vector<Body>& bodies, const std::vector<char>& loaded)
{
    for (size_t i = 0; i < bodies.size(); ++i)
        if (loaded[i]) wake(bodies[i]);
}

void wakeBodiesHitByMovers(std::vector<Body>& bodies, const std::vector<ContactManifold>& manifolds, const SleepSettings& sleep)
{
    auto wakes = [&](const Body& mover) { return takesContactImpulses(mover) && maxVoxelSpeedMS(mover) > sleep.speedMS; };
    for (const ContactManifold& m : manifolds) {
        Body& a = bodies[m.a];
        Body& b = bodies[m.b];
        for (auto [sleeper, other] : {std::pair<Body*, Body*>{&a, &b}, std::pair<Body*, Body*>{&b, &a}})
            if (sleeper->motion.asleep && !sleeper->anchored && wakes(*other)) wake(*sleeper);
    }
}

void updateSleep(std::vector<Body>& bodies, const std::vector<BodyPair>& touching, const std::vector<char>& loaded,
                 const SleepSettings& sleep, double dt)
{
    if (!sleep.enabled) return;
    for (size_t i = 0; i < bodies.size(); ++i) {
        Body& b = bodies[i];
        if (b.anchored || b.motion.asleep) continue;
        const bool resting = !loaded[i] && !b.motion.deformable && maxVoxelSpeedMS(b) < sleep.speedMS;
        b.motion.restTimeS = resting ? b.motion.restTimeS + dt : 0.0;
    }
    DisjointSets islands(bodies.size());
    for (const BodyPair& p : touching)
        if (!bodies[p.a].anchored && !bodies[p.b].anchored) islands.join(uint32_t(p.a), uint32_t(p.b));
    std::vector<char> restless(bodies.size(), 0);
    for (size_t i = 0; i < bodies.size(); ++i)
        if (!bodies[i].anchored && !bodies[i].motion.asleep && bodies[i].motion.restTimeS < sleep.timeS) restless[islands.root(uint32_t(i))] = 1;
    for (size_t i = 0; i < bodies.size(); ++i) {
        Body& b = bodies[i];
        if (b.anchored || b.motion.asleep || restless[islands.root(uint32_t(i))]) continue;
        b.motion.asleep = true;
        b.motion.linearVelocityMS.setZero();
        b.motion.angularVelocityRadS.setZero();
    }
}

}  // namespace spall
