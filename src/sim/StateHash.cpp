// A content hash of a simulation's state, for the golden tests that hold refactors to bit-identical
// outputs (tests/test_golden.cpp).
#include <spall/sim/Simulation.h>

#include <spall/core/Hash.h>

#include <cstring>

namespace spall {

namespace {

/// Folds values into a running hash, each through splitmix64 (core/Hash.h), by their bits: two
/// states hash alike only when every number is the same to the last bit.
class StateHasher {
public:
    void add(uint64_t bits) { mHash = splitmix64(mHash ^ bits); }
    void add(int64_t value) { add(static_cast<uint64_t>(value)); }
    void add(double value)
    {
        uint64_t bits = 0;
        std::memcpy(&bits, &value, sizeof bits);
        add(bits);
    }
    void add(const Eigen::Vector3d& v)
    {
        for (int k = 0; k < 3; ++k) add(v[k]);
    }
    void add(const Eigen::Quaterniond& q)
    {
        for (int k = 0; k < 4; ++k) add(q.coeffs()[k]);
    }
    void addBody(const Body& body)
    {
        add(body.id);
        add(body.parentId);
        add(int64_t(body.materialIndex));
        add(body.motion.positionM);
        add(body.motion.orientation);
        add(body.motion.linearVelocityMS);
        add(body.motion.angularVelocityRadS);
        add(int64_t(body.motion.asleep) | int64_t(body.motion.deformable) << 1 | int64_t(body.anchored) << 2);
        add(body.mass.voxelCount);
        // Which voxels are solid and what links them, in the tree's own (deterministic) order.
        for (auto it = body.grid->cbeginValueOn(); it; ++it) {
            const openvdb::Coord& c = it.getCoord();
            add(int64_t(c.x()) << 42 ^ int64_t(c.y()) << 21 ^ int64_t(c.z()));
            add(int64_t(*it));
        }
        // What the deformable phase left in its surviving bonds.
        if (body.linkDamage)
            for (auto it = body.linkDamage->cbeginValueOn(); it; ++it)
                for (int c = 0; c < 4; ++c) add(double((*it)[c]));
    }
    uint64_t value() const { return mHash; }

private:
    uint64_t mHash = 0;
};

}  // namespace

uint64_t stateHash(const SimulationState& state)
{
    StateHasher h;
    h.add(state.timeS);
    h.add(state.nextId);
    h.add(int64_t(state.bodies.size()));
    for (const Body& body : state.bodies) h.addBody(body);
    h.add(int64_t(state.events.size()));
    for (const FractureEvent& event : state.events) {
        h.add(event.timeS);
        h.add(event.parentId);
        for (int64_t child : event.childIds) h.add(child);
    }
    h.add(int64_t(state.dust.size()));
    for (const DustRecord& dust : state.dust) h.add(dust.linearMomentum);
    h.add(int64_t(state.handOffs.size()));
    for (const HandOffRecord& r : state.handOffs) {
        h.add(r.timeS);
        h.add(r.bodyId);
        h.add(r.brokenBonds);
        h.add(r.discardedEnergyJ);
    }
    return h.value();
}

}  // namespace spall
