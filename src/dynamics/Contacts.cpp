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
    forEachIndex(bodies.size(), [&](size_t i) {
        if (movable(bodies[i])) set.statics[i] = findStaticContacts(bodies[i], world);
    });
    for (const std::vector<StaticContact>& s : set.statics) set.staticContacts += static_cast<int64_t>(s.size());
    set.solverContacts = set.staticContacts;
    for (const ContactManifold& m : set.manifolds) {
        set.solverContacts += static_cast<int64_t>(m.points.size());
        set.bodyContacts += m.voxelContacts;
        set.maxPenetrationM = std::max(set.maxPenetrationM, m.maxDepthM);
        set.touching.push_back({m.a, m.b});
    }
    return set;
}

}  // namespace spall
