#include <spall/sim/Checkpoint.h>

#include <spall/core/AtomicFile.h>
#include <spall/voxel/VdbIo.h>

#include <openvdb/io/Stream.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <type_traits>

namespace spall {

namespace {

constexpr char kMagic[8] = {'S', 'P', 'A', 'L', 'L', 'C', 'K', 'P'};

// Writer and Reader offer the same calls; `transferFields` lists the fields once and runs with
// either, so what is written and what is read cannot drift apart.
class Writer {
public:
    static constexpr bool kReading = false;
    explicit Writer(std::ostream& out) : mOut(out) {}
    template <typename T>
    void pod(const T& value, const char*)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        mOut.write(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    void flag(bool value, const char* what) { pod<uint8_t>(value, what); }
    void doubles(const double* values, int n, const char*) { mOut.write(reinterpret_cast<const char*>(values), n * sizeof(double)); }
    void vec(const Eigen::Vector3d& v, const char* what) { doubles(v.data(), 3, what); }
    void text(const std::string& s, const char* what)
    {
        pod<uint64_t>(s.size(), what);
        mOut.write(s.data(), static_cast<std::streamsize>(s.size()));
    }
    /// Its size, then each element.
    template <typename Sequence, typename F>
    void sequence(const Sequence& items, const char* what, F&& each)
    {
        pod<uint64_t>(items.size(), what);
        for (const auto& item : items) each(item);
    }

private:
    std::ostream& mOut;
};

class Reader {
public:
    static constexpr bool kReading = true;
    Reader(std::istream& in, std::string path) : mIn(in), mPath(std::move(path))
    {
        const auto here = mIn.tellg();
        mIn.seekg(0, std::ios::end);
        mSize = static_cast<uint64_t>(mIn.tellg());
        mIn.seekg(here);
    }
    template <typename T>
    void pod(T& value, const char* what)
    {
        mIn.read(reinterpret_cast<char*>(&value), sizeof(T));
        check(what);
    }
    void flag(bool& value, const char* what)
    {
        uint8_t byte = 0;
        pod(byte, what);
        value = byte != 0;
    }
    void doubles(double* values, int n, const char* what)
    {
        mIn.read(reinterpret_cast<char*>(values), n * sizeof(double));
        check(what);
    }
    void vec(Eigen::Vector3d& v, const char* what) { doubles(v.data(), 3, what); }
    void text(std::string& s, const char* what)
    {
        s.assign(count(what), '\0');
        mIn.read(s.data(), static_cast<std::streamsize>(s.size()));
        check(what);
    }
    template <typename Sequence, typename F>
    void sequence(Sequence& items, const char* what, F&& each)
    {
        items.resize(count(what));
        for (auto& item : items) each(item);
    }
    /// A count, refused when the rest of the file could not hold that many elements (every
    /// element takes at least a byte): a corrupt file must not allocate the world.
    uint64_t count(const char* what)
    {
        uint64_t n = 0;
        pod(n, what);
        const uint64_t left = mSize - static_cast<uint64_t>(mIn.tellg());
        if (n > left) fail(std::string(what) + " count " + std::to_string(n) + " exceeds what is left of the file");
        return n;
    }
    [[noreturn]] void fail(const std::string& why) const { throw IoError(mPath + ": corrupt checkpoint: " + why); }

private:
    void check(const char* what)
    {
        if (!mIn) fail(std::string("truncated while reading ") + what);
    }
    std::istream& mIn;
    std::string mPath;
    uint64_t mSize = 0;
};

/// A body in the deformable phase: the particles' state, the forces velocity Verlet carries and
/// the bonds' history; the rest follows from the body's grid (restoreDeformable).
template <typename Archive, typename D>
void transferDeformable(Archive& a, D& d)
{
    a.pod(d.bodyId, "deformable body");
    a.pod(d.enteredS, "deformable since");
    a.pod(d.lastLoadedS, "deformable last loaded");
    a.pod(d.awaitedImpactS, "deformable awaited impact");
    a.pod(d.awaitImpactUntilS, "deformable awaits impact until");
    a.flag(d.coasting, "deformable coasting");
    a.pod(d.blocks.voxels, "particle voxels");
    a.vec(d.entryPositionM, "deformable entry position");
    a.doubles(d.entryOrientation.coeffs().data(), 4, "deformable entry orientation");
    for (int axis = 0; axis < 3; ++axis) a.pod(d.blocks.origin[axis], "particle blocks' origin");
    a.sequence(d.shownIdOfParticle, "shown ids", [&](auto& id) { a.pod(id, "shown id"); });
    auto& lattice = d.lattice;
    a.sequence(lattice.state.positionM, "particle positions", [&](auto& v) { a.vec(v, "particle position"); });
    a.sequence(lattice.state.velocityMS, "particle velocities", [&](auto& v) { a.vec(v, "particle velocity"); });
    a.sequence(lattice.state.angularVelocityRadS, "particle spins", [&](auto& v) { a.vec(v, "particle spin"); });
    a.sequence(lattice.state.orientation, "particle orientations", [&](auto& q) { a.doubles(q.coeffs().data(), 4, "particle orientation"); });
    a.sequence(lattice.state.bondForceN, "particle bond forces", [&](auto& v) { a.vec(v, "particle bond force"); });
    a.sequence(lattice.state.bondMomentNm, "particle bond moments", [&](auto& v) { a.vec(v, "particle bond moment"); });
    a.pod(d.pendingS, "deformable gathered time");
    a.sequence(d.pendingImpulseNs, "particle gathered impulses", [&](auto& v) { a.vec(v, "particle gathered impulse"); });
    a.sequence(lattice.state.bondHistory, "bond histories", [&](auto& h) {
        a.pod(h.strengthScale, "bond strength");
        a.pod(h.maxEquivalentStretchM, "bond stretch");
        a.pod(h.strengthFactor, "bond strength factor");
        a.pod(h.rateWeightedStretchM, "bond rate-weighted stretch");
        a.pod(h.rateDamage, "bond damage");
        a.pod(h.maxCrushingShorteningM, "bond crushing");
    });
}

template <typename Archive, typename H>
void transferHandOff(Archive& a, H& h)
{
    a.pod(h.timeS, "hand-off time");
    a.pod(h.bodyId, "hand-off body");
    a.pod(h.particles, "hand-off particles");
    a.pod(h.brokenBonds, "hand-off broken bonds");
    a.pod(h.brokenAnchors, "hand-off broken anchors");
    a.pod(h.deformableS, "hand-off duration");
    a.pod(h.discardedEnergyJ, "hand-off energy");
    a.flag(h.timedOut, "hand-off timed out");
}

template <typename Archive, typename E>
void transferPairOverlapExcuse(Archive& a, E& e)
{
    a.pod(e.bodyIdA, "lattice pair body");
    a.pod(e.bodyIdB, "lattice pair body");
    a.pod(e.excuseM, "lattice pair overlap excuse");
}

/// Every field but the grids, in file order. `C` is `const Checkpoint` when writing.
/// `extraGrids[i]` says which grids besides its links body i has (kDamageGrid, kLinkDamageGrid).
template <typename Archive, typename C>
void transferFields(Archive& a, C& c, std::vector<uint8_t>& extraGrids)
{
    auto& s = c.state;
    a.pod(c.framesDone, "frames done");
    a.pod(c.frameCount, "frame count");
    a.pod(c.totalSteps, "total steps");
    a.text(c.sceneJson, "scene");
    a.pod(c.written.fractureEvents, "fracture events written");
    a.pod(c.written.dust, "dust records written");
    a.pod(s.timeS, "time");
    a.pod(s.nextId, "next id");
    a.pod(s.initialVoxels, "initial voxels");
    a.pod(s.penetrationStepScale, "step scale");
    a.pod(s.stepStats.steps, "frame steps");
    a.pod(s.stepStats.minDtS, "frame smallest step");
    a.pod(s.stepStats.brokenLinks, "frame broken links");
    a.pod(s.stepStats.latticeParticleSteps, "frame lattice particle-steps");
    size_t index = 0;
    a.sequence(s.bodies, "bodies", [&](auto& b) {
        a.pod(b.id, "body id");
        a.pod(b.parentId, "parent id");
        a.pod(b.materialIndex, "material");
        a.pod(b.voxelSizeM, "voxel size");
        a.pod(b.densityKgM3, "density");
        a.vec(b.motion.positionM, "position");
        a.doubles(b.motion.orientation.coeffs().data(), 4, "orientation");
        a.vec(b.motion.linearVelocityMS, "velocity");
        a.vec(b.motion.angularVelocityRadS, "angular velocity");
        a.flag(b.motion.asleep, "asleep");
        a.flag(b.motion.deformable, "deformable");
        a.pod(b.motion.restTimeS, "rest time");
        a.pod(b.motion.survivedImpactMS, "survived impact");
        a.pod(b.motion.overlapSlackM, "overlap slack");
        // Mass, faces, bounds, link count and anchoring are derived from the grid on reading.
        if constexpr (Archive::kReading) extraGrids.resize(index + 1);
        a.pod(extraGrids[index++], "damage grids");
    });
    a.sequence(s.events, "events", [&](auto& e) {
        a.pod(e.timeS, "event time");
        a.pod(e.parentId, "event parent");
        a.sequence(e.childIds, "event children", [&](auto& id) { a.pod(id, "event child"); });
    });
    a.sequence(s.dust, "dust", [&](auto& d) {
        a.pod(d.timeS, "dust time");
        a.pod(d.parentId, "dust parent");
        a.pod(d.voxelCount, "dust voxels");
        a.pod(d.massKg, "dust mass");
        a.vec(d.linearMomentum, "dust momentum");
        a.vec(d.angularMomentumAboutOrigin, "dust angular momentum");
    });
    a.sequence(s.deformable.lattices, "deformable bodies", [&](auto& d) { transferDeformable(a, d); });
    a.sequence(s.deformable.pairOverlapExcuses, "lattice pairs", [&](auto& e) { transferPairOverlapExcuse(a, e); });
    a.sequence(s.handOffs, "hand-offs", [&](auto& h) { transferHandOff(a, h); });
    a.sequence(s.contactCache.points, "contact points", [&](auto& p) {
        a.pod(p.key.first, "contact key");
        a.pod(p.key.second, "contact key");
        a.vec(p.localM, "contact point");
        a.pod(p.normalNs, "normal impulse");
        a.vec(p.frictionNs, "friction impulse");
    });
}

std::string gridName(const char* kind, size_t body) { return std::string(kind) + "_" + std::to_string(body); }

/// Which of a body's optional grids a checkpoint holds (bits of its "damage grids" byte).
constexpr uint8_t kDamageGrid = 1, kLinkDamageGrid = 2;

}  // namespace

void writeCheckpoint(const std::string& path, const Checkpoint& c)
{
    const SimulationState& s = c.state;
    std::vector<uint8_t> extraGrids(s.bodies.size());
    openvdb::GridCPtrVec grids;
    // Each a copy that shares the tree; only the name differs.
    const auto add = [&](const auto& grid, const char* kind, size_t i) {
        auto named = grid->copyGrid();
        named->setName(gridName(kind, i));
        grids.push_back(named);
    };
    for (size_t i = 0; i < s.bodies.size(); ++i) {
        const Body& b = s.bodies[i];
        add(b.grid, "links", i);
        if (b.damage) add(b.damage, "damage", i);
        if (b.linkDamage) add(b.linkDamage, "link_damage", i);
        extraGrids[i] = uint8_t((b.damage ? kDamageGrid : 0) | (b.linkDamage ? kLinkDamageGrid : 0));
    }
    initialiseOpenVdb();
    std::ostringstream vdb(std::ios::binary);
    openvdb::io::Stream(vdb).write(grids);

    // Straight into the file, not through a buffer of the whole: a lattice of 3 M particles makes
    // a checkpoint of 0.74 GB, and a buffer with its copy tripled the run's peak memory.
    writeFileAtomically(path, [&](std::ostream& out) {
        Writer w(out);
        out.write(kMagic, sizeof kMagic);
        w.pod(kCheckpointFormatVersion, "version");
        transferFields(w, c, extraGrids);
        w.text(vdb.str(), "grids");
        out.write(kMagic, sizeof kMagic);  // a trailer: a file cut short is recognised
    });
}

Checkpoint readCheckpoint(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw IoError(path + ": no checkpoint (none was written yet, or the file cannot be opened)");
    Reader r(in, path);
    char magic[sizeof kMagic];
    in.read(magic, sizeof magic);
    if (!in || std::memcmp(magic, kMagic, sizeof kMagic) != 0) r.fail("not a spall checkpoint");
    uint32_t version = 0;
    r.pod(version, "version");
    if (version != kCheckpointFormatVersion)
        throw IoError(path + ": checkpoint format version " + std::to_string(version) + " is not the supported " +
                      std::to_string(kCheckpointFormatVersion));
    Checkpoint c;
    std::vector<uint8_t> extraGrids;
    transferFields(r, c, extraGrids);
    const auto& cached = c.state.contactCache.points;
    if (!std::is_sorted(cached.begin(), cached.end(), [](const ContactCache::Point& x, const ContactCache::Point& y) { return x.key < y.key; }))
        r.fail("contact points out of order");
    if (c.framesDone < 1 || c.frameCount < c.framesDone)
        r.fail("frames done " + std::to_string(c.framesDone) + " of " + std::to_string(c.frameCount));
    if (c.written.fractureEvents < 0 || size_t(c.written.fractureEvents) > c.state.events.size() || c.written.dust < 0 ||
        size_t(c.written.dust) > c.state.dust.size())
        r.fail("the frames hold " + std::to_string(c.written.fractureEvents) + " fracture events and " + std::to_string(c.written.dust) +
               " dust records, more than the state's " + std::to_string(c.state.events.size()) + " and " + std::to_string(c.state.dust.size()));
    SimulationState& s = c.state;
    std::string vdbBytes;
    r.text(vdbBytes, "grids");
    std::istringstream vdb(vdbBytes, std::ios::binary);
    char trailer[sizeof kMagic];
    in.read(trailer, sizeof trailer);
    if (!in || std::memcmp(trailer, kMagic, sizeof kMagic) != 0) r.fail("the trailer is missing (the file is cut short)");

    initialiseOpenVdb();
    openvdb::GridPtrVecPtr grids;
    try {
        grids = openvdb::io::Stream(vdb, false).getGrids();
    } catch (const std::exception& e) {
        r.fail(std::string("its grids do not read: ") + e.what());
    }
    std::unordered_map<std::string, openvdb::GridBase::Ptr> byName;
    for (const auto& g : *grids) byName[g->getName()] = g;
    for (size_t i = 0; i < s.bodies.size(); ++i) {
        Body& b = s.bodies[i];
        b.grid = openvdb::gridPtrCast<LinkGrid>(byName[gridName("links", i)]);
        if (!b.grid) r.fail("the link grid of body " + std::to_string(i) + " is missing");
        refreshDerivedData(b);
        if (extraGrids[i] & kDamageGrid) {
            b.damage = openvdb::gridPtrCast<DamageGrid>(byName[gridName("damage", i)]);
            if (!b.damage) r.fail("the damage grid of body " + std::to_string(i) + " is missing");
        }
        if (extraGrids[i] & kLinkDamageGrid) {
            b.linkDamage = openvdb::gridPtrCast<LinkDamageGrid>(byName[gridName("link_damage", i)]);
            if (!b.linkDamage) r.fail("the link damage grid of body " + std::to_string(i) + " is missing");
        }
    }
    return c;
}

}  // namespace spall
