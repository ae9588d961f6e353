#include <spall/sim/Checkpoint.h>

#include <spall/io/VdbIo.h>

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

class Writer {
public:
    explicit Writer(std::ostream& out) : mOut(out) {}
    template <typename T>
    void pod(const T& value)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        mOut.write(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    void doubles(const double* values, int n) { mOut.write(reinterpret_cast<const char*>(values), n * sizeof(double)); }
    void vec(const Eigen::Vector3d& v) { doubles(v.data(), 3); }
    void text(const std::string& s)
    {
        pod<uint64_t>(s.size());
        mOut.write(s.data(), static_cast<std::streamsize>(s.size()));
    }

private:
    std::ostream& mOut;
};

class Reader {
public:
    Reader(std::istream& in, std::string path) : mIn(in), mPath(std::move(path)) {}
    template <typename T>
    T pod(const char* what)
    {
        T value{};
        mIn.read(reinterpret_cast<char*>(&value), sizeof(T));
        check(what);
        return value;
    }
    void doubles(double* values, int n, const char* what)
    {
        mIn.read(reinterpret_cast<char*>(values), n * sizeof(double));
        check(what);
    }
    Eigen::Vector3d vec(const char* what)
    {
        Eigen::Vector3d v;
        doubles(v.data(), 3, what);
        return v;
    }
    std::string text(const char* what)
    {
        const uint64_t n = count(what, uint64_t(1) << 34);
        std::string s(n, '\0');
        mIn.read(s.data(), static_cast<std::streamsize>(n));
        check(what);
        return s;
    }
    /// A count, refused when it exceeds `limit` (a corrupt file must not allocate the world).
    uint64_t count(const char* what, uint64_t limit = uint64_t(1) << 32)
    {
        const uint64_t n = pod<uint64_t>(what);
        if (n > limit) fail(std::string(what) + " count " + std::to_string(n) + " is implausible");
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
};

std::string gridName(const char* kind, size_t body) { return std::string(kind) + "_" + std::to_string(body); }

}  // namespace

void writeCheckpoint(const std::string& path, const Checkpoint& c)
{
    const SimulationState& s = c.state;
    std::ostringstream buffer(std::ios::binary);
    Writer w(buffer);
    buffer.write(kMagic, sizeof kMagic);
    w.pod(kCheckpointFormatVersion);
    w.pod<int32_t>(c.framesDone);
    w.pod<int32_t>(c.frameCount);
    w.pod(c.totalSteps);
    w.text(c.sceneJson);
    w.pod(s.timeS);
    w.pod(s.nextId);
    w.pod(s.initialVoxels);
    w.pod(s.penetrationStepScale);

    w.pod<uint64_t>(s.bodies.size());
    for (size_t i = 0; i < s.bodies.size(); ++i) {
        const Body& b = s.bodies[i];
        w.pod(b.id);
        w.pod(b.parentId);
        w.pod<int32_t>(b.materialIndex);
        w.pod(b.voxelSizeM);
        w.pod(b.densityKgM3);
        w.pod(b.linkCount);
        w.pod<uint8_t>(b.anchored);
        w.vec(b.positionM);
        w.doubles(b.orientation.coeffs().data(), 4);
        w.vec(b.linearVelocityMS);
        w.vec(b.angularVelocityRadS);
        w.pod<uint8_t>(b.asleep);
        w.pod(b.restTimeS);
        // Mass properties as they were: recomputing them would give the same bits, but a
        // checkpoint should not depend on that.
        w.pod(b.mass.voxelCount);
        w.pod(b.mass.massKg);
        w.vec(b.mass.centreOfMassLocalM);
        w.doubles(b.mass.inertiaKgM2.data(), 9);
        w.pod(b.boundingRadiusM);
        w.pod<uint8_t>(i < s.damage.size() && s.damage[i] != nullptr);
    }
    w.pod<uint64_t>(s.events.size());
    for (const FractureEvent& e : s.events) {
        w.pod(e.timeS);
        w.pod(e.parentId);
        w.pod<uint64_t>(e.childIds.size());
        for (int64_t id : e.childIds) w.pod(id);
    }
    w.pod<uint64_t>(s.dust.size());
    for (const DustRecord& d : s.dust) {
        w.pod(d.timeS);
        w.pod(d.parentId);
        w.pod(d.voxelCount);
        w.pod(d.massKg);
        w.vec(d.linearMomentum);
        w.vec(d.angularMomentumAboutOrigin);
    }
    // The contact cache in key order, so the file does not depend on hash-table order.
    std::vector<std::pair<int64_t, int64_t>> keys;
    for (const auto& entry : s.contactCache.points) keys.push_back(entry.first);
    std::sort(keys.begin(), keys.end());
    w.pod<uint64_t>(keys.size());
    for (const auto& key : keys) {
        const auto& points = s.contactCache.points.at(key);
        w.pod(key.first);
        w.pod(key.second);
        w.pod<uint64_t>(points.size());
        for (const ContactCache::Point& p : points) {
            w.vec(p.localM);
            w.pod(p.normalNs);
            w.vec(p.frictionNs);
        }
    }
    openvdb::GridCPtrVec grids;
    for (size_t i = 0; i < s.bodies.size(); ++i) {
        auto links = s.bodies[i].grid->copyGrid();  // shares the tree; only the name differs
        links->setName(gridName("links", i));
        grids.push_back(links);
        if (i < s.damage.size() && s.damage[i]) {
            auto damage = s.damage[i]->copyGrid();
            damage->setName(gridName("damage", i));
            grids.push_back(damage);
        }
    }
    initialiseOpenVdb();
    std::ostringstream vdb(std::ios::binary);
    openvdb::io::Stream(vdb).write(grids);
    w.text(vdb.str());
    buffer.write(kMagic, sizeof kMagic);  // a trailer: a file cut short is recognised

    const std::string temporary = path + ".partial";
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        const std::string bytes = buffer.str();
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.flush();
        if (!out) {
            out.close();
            std::error_code ec;
            std::filesystem::remove(temporary, ec);
            throw IoError(path + ": cannot write the checkpoint (disk full or not writable?)");
        }
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) throw IoError(path + ": cannot rename the checkpoint into place: " + ec.message());
}

Checkpoint readCheckpoint(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path + ": no checkpoint to resume from (the run stopped before its first frame was complete, had output.checkpoint_every_frames 0, or finished)");
    Reader r(in, path);
    char magic[sizeof kMagic];
    in.read(magic, sizeof magic);
    if (!in || std::memcmp(magic, kMagic, sizeof kMagic) != 0) r.fail("not a spall checkpoint");
    const uint32_t version = r.pod<uint32_t>("version");
    if (version != kCheckpointFormatVersion)
        throw IoError(path + ": checkpoint format version " + std::to_string(version) + " is not the supported " +
                      std::to_string(kCheckpointFormatVersion));
    Checkpoint c;
    SimulationState& s = c.state;
    c.framesDone = r.pod<int32_t>("frames done");
    c.frameCount = r.pod<int32_t>("frame count");
    if (c.framesDone < 1 || c.frameCount < c.framesDone) r.fail("frames done " + std::to_string(c.framesDone) + " of " + std::to_string(c.frameCount));
    c.totalSteps = r.pod<int64_t>("total steps");
    c.sceneJson = r.text("scene");
    s.timeS = r.pod<double>("time");
    s.nextId = r.pod<int64_t>("next id");
    s.initialVoxels = r.pod<int64_t>("initial voxels");
    s.penetrationStepScale = r.pod<double>("step scale");

    const uint64_t bodyCount = r.count("bodies");
    std::vector<char> hasDamage(bodyCount);
    s.bodies.resize(bodyCount);
    for (uint64_t i = 0; i < bodyCount; ++i) {
        Body& b = s.bodies[i];
        b.id = r.pod<int64_t>("body id");
        b.parentId = r.pod<int64_t>("parent id");
        b.materialIndex = r.pod<int32_t>("material");
        b.voxelSizeM = r.pod<double>("voxel size");
        b.densityKgM3 = r.pod<double>("density");
        b.linkCount = r.pod<int64_t>("link count");
        b.anchored = r.pod<uint8_t>("anchored") != 0;
        b.positionM = r.vec("position");
        r.doubles(b.orientation.coeffs().data(), 4, "orientation");
        b.linearVelocityMS = r.vec("velocity");
        b.angularVelocityRadS = r.vec("angular velocity");
        b.asleep = r.pod<uint8_t>("asleep") != 0;
        b.restTimeS = r.pod<double>("rest time");
        b.mass.voxelCount = r.pod<int64_t>("voxel count");
        b.mass.massKg = r.pod<double>("mass");
        b.mass.centreOfMassLocalM = r.vec("centre of mass");
        r.doubles(b.mass.inertiaKgM2.data(), 9, "inertia");
        b.boundingRadiusM = r.pod<double>("bounding radius");
        hasDamage[i] = r.pod<uint8_t>("damage flag");
    }
    s.events.resize(r.count("events"));
    for (FractureEvent& e : s.events) {
        e.timeS = r.pod<double>("event time");
        e.parentId = r.pod<int64_t>("event parent");
        e.childIds.resize(r.count("event children"));
        for (int64_t& id : e.childIds) id = r.pod<int64_t>("event child");
    }
    s.dust.resize(r.count("dust"));
    for (DustRecord& d : s.dust) {
        d.timeS = r.pod<double>("dust time");
        d.parentId = r.pod<int64_t>("dust parent");
        d.voxelCount = r.pod<int64_t>("dust voxels");
        d.massKg = r.pod<double>("dust mass");
        d.linearMomentum = r.vec("dust momentum");
        d.angularMomentumAboutOrigin = r.vec("dust angular momentum");
    }
    const uint64_t pairs = r.count("contact pairs");
    for (uint64_t k = 0; k < pairs; ++k) {
        const int64_t a = r.pod<int64_t>("contact key"), b = r.pod<int64_t>("contact key");
        auto& points = s.contactCache.points[{a, b}];
        points.resize(r.count("contact points"));
        for (ContactCache::Point& p : points) {
            p.localM = r.vec("contact point");
            p.normalNs = r.pod<double>("normal impulse");
            p.frictionNs = r.vec("friction impulse");
        }
    }
    std::istringstream vdb(r.text("grids"), std::ios::binary);
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
    s.damage.resize(bodyCount);
    for (uint64_t i = 0; i < bodyCount; ++i) {
        Body& b = s.bodies[i];
        b.grid = openvdb::gridPtrCast<LinkGrid>(byName[gridName("links", i)]);
        if (!b.grid) r.fail("the link grid of body " + std::to_string(i) + " is missing");
        b.exposedFaces = collectExposedFaces(*b.grid);
        b.boundaryVoxels = boundaryVoxelsOf(b.exposedFaces);
        b.indexBounds = b.grid->evalActiveVoxelBoundingBox();
        if (hasDamage[i]) {
            s.damage[i] = openvdb::gridPtrCast<DamageGrid>(byName[gridName("damage", i)]);
            if (!s.damage[i]) r.fail("the damage grid of body " + std::to_string(i) + " is missing");
        }
    }
    return c;
}

}  // namespace spall
