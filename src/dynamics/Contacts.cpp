#include <spall/dynamics/Contacts.h>

#include <spall/core/Parallel.h>
#include <spall/dynamics/Integrate.h>
#include <spall/dynamics/Sleep.h>

#include <algorithm>

namespace spall {

ContactSet detectContacts(std::vector<Body>& bodies, const WorldSettings& world, const CollisionSettings& collisions,
                          const SleepSettings& sleep)
{
    ContactSet set;
    set.manifolds = findBodyContacts(bodies, collisions.method);
    wakeBodiesHitByMovers(bodies, set.manifolds, sleep);
    set.statics.resize(bodies.size());
    // A lattice keeps its particles above the ground itself; the boxes it meets as a rigid body.
    WorldSettings boxesOnly = world;
    boxesOnly.ground.enabled = false;
    forEachIndex(bodies.size(), [&](size_t i) {
        if (movable(bodies[i]))
            set.statics[i] = findStaticContacts(bodies[i], world);
        else if (takesContactImpulses(bodies[i]))
            set.statics[i] = findStaticContacts(bodies[i], boxesOnly);
    });
    for (const std::vector<StaticContact>& s : set.statics) set.staticContacts += static_cast<int64_t>(s.size());
    set.solverContacts = set.staticContacts;
    for (const ContactManifold& m : set.manifolds) {
        set.solverContacts += static_cast<int64_t>(m.points.size());
        set.bodyContacts += m.voxelContacts;
        set.touching.push_back({m.a, m.b});
    }
    return set;
}

double impactSpeedMS(const WorldSettings& world, double dtS) { return 2.0 * world.gravityMS2.norm() * dtS + 0.05; }

double tunnellingSpeedMS(const WorldSettings& world, double dtS, double voxelSizeM)
{
    constexpr double kDeepeningPerStepVoxels = 0.05;
    return std::max(impactSpeedMS(world, dtS), kDeepeningPerStepVoxels * voxelSizeM / dtS);
}

double fastestClosingSpeedMS(const std::vector<Body>& bodies, const ContactManifold& manifold)
{
    const BodyMotion& a = bodies[size_t(manifold.a)].motion;
    const BodyMotion& b = bodies[size_t(manifold.b)].motion;
    double fastestMS = 0.0;
    for (const VoxelContact& p : manifold.points) {
        const Eigen::Vector3d va = a.linearVelocityMS + a.angularVelocityRadS.cross(p.pointM - a.positionM);
        const Eigen::Vector3d vb = b.linearVelocityMS + b.angularVelocityRadS.cross(p.pointM - b.positionM);
        fastestMS = std::max(fastestMS, -manifold.normal.dot(va - vb));  // the normal points from b to a
    }
    return fastestMS;
}

double deepestClosingPenetrationM(const std::vector<Body>& bodies, const ContactSet& contacts, double closingSpeedMS)
{
    double deepestM = 0.0;
    for (const ContactManifold& m : contacts.manifolds)
        if (m.maxDepthM > deepestM && fastestClosingSpeedMS(bodies, m) > closingSpeedMS) deepestM = m.maxDepthM;
    return deepestM;
}

}  // namespace spall
