#include <spall/io/VdbIo.h>

#include <spall/core/AtomicFile.h>

#include <spall/core/Error.h>

#include <openvdb/io/Archive.h>
#include <openvdb/io/File.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <unistd.h>
#include <unordered_set>

namespace spall {

void initialiseOpenVdb()
{
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        // spall's own tree shapes, so checkpoints can stream them.
        if (!LinkGrid::isRegistered()) LinkGrid::registerGrid();
        if (!DamageGrid::isRegistered()) DamageGrid::registerGrid();
    });
}

namespace {

/// openvdb::io::File writes through a stream it never checks, so a full disk leaves a truncated
/// file that looks whole. This writes the same seekable format into a stream we can check.
class CheckedVdbWriter : public openvdb::io::Archive {
public:
    void writeTo(std::ostream& out, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& metadata) const
    {
        Archive::write(out, grids, /*seekable=*/true, metadata);
    }
};

}  // namespace

void writeGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& fileMetadata)
{
    initialiseOpenVdb();
    writeFileAtomically(path, [&](std::ostream& out) {
        CheckedVdbWriter writer;
        writer.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        writer.writeTo(out, grids, fileMetadata);
    });
}

void writeVoxelisedBody(const std::string& path, const LinkGrid& grid, double voxelSizeM, const std::string& source,
                        const std::string& material)
{
    // Link bits as exact small integers in a FloatGrid: Python's pyopenvdb cannot even list a
    // file that holds an Int32 grid.
    auto links = openvdb::FloatGrid::create(0.0f);
    for (auto leaf = grid.constTree().cbeginLeaf(); leaf; ++leaf) {
        auto* target = links->tree().touchLeaf(leaf->origin());
        for (auto it = leaf->cbeginValueOn(); it; ++it) target->setValueOn(it.pos(), static_cast<float>(*it & (kAllLinks | kAnchorBit)));
    }
    links->setTransform(grid.transform().copy());
    links->setName("links");
    auto solid = openvdb::FloatGrid::create(0.0f);
    copyActiveTopology(solid->tree(), grid.constTree(), 1.0f);
    solid->setTransform(grid.transform().copy());
    solid->setName("solid");
    solid->setGridClass(openvdb::GRID_FOG_VOLUME);
    for (openvdb::GridBase* g : {static_cast<openvdb::GridBase*>(solid.get()), static_cast<openvdb::GridBase*>(links.get())}) {
        g->insertMeta("voxel_size_m", openvdb::DoubleMetadata(voxelSizeM));
        g->insertMeta("source", openvdb::StringMetadata(source));
        g->insertMeta("material", openvdb::StringMetadata(material));
        g->insertMeta("spall_version", openvdb::StringMetadata(SPALL_VERSION));
    }
    writeGridsAtomically(path, {solid, links});
}

LinkGrid::Ptr readLinkGrid(const std::string& path)
{
    initialiseOpenVdb();
    try {
        openvdb::io::File file(path);
        file.open();
        openvdb::GridPtrVecPtr grids = file.getGrids();
        file.close();
        for (const auto& g : *grids) {
            auto links = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
            if (!links || links->getName() != "links") continue;
            auto out = LinkGrid::create(0);
            out->setTransform(links->transform().copy());
            out->setName("links");
            out->insertMeta(*links);
            openvdb::FloatTree voxels(links->tree());
            voxels.voxelizeActiveTiles();
            for (auto leaf = voxels.cbeginLeaf(); leaf; ++leaf) {
                auto* target = out->tree().touchLeaf(leaf->origin());
                for (auto it = leaf->cbeginValueOn(); it; ++it) target->setValueOn(it.pos(), static_cast<int32_t>(*it));
            }
            return out;
        }
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read as .vdb: " + e.what());
    }
    throw IoError(path + ": holds no grid named 'links' (not written by spall voxelise?)");
}


FrameWriter::FrameWriter(std::string outputDirectory, bool densityGrid)
    : mDirectory(std::move(outputDirectory)), mDensityGrid(densityGrid)
{
}

std::string FrameWriter::framePath(const std::string& directory, int frame)
{
    char name[64];
    std::snprintf(name, sizeof name, "fragments.%04d.vdb", frame);
    return (std::filesystem::path(directory) / name).string();
}

const FrameWriter::Solid& FrameWriter::solidOf(const Body& body)
{
    auto found = mSolids.find(body.id);
    if (found != mSolids.end()) return found->second;
    const openvdb::Coord origin = body.indexBounds.min();
    auto tree = std::make_shared<openvdb::FloatTree>(0.0f);
    {
        openvdb::tree::ValueAccessor<openvdb::FloatTree> acc(*tree);
        for (auto it = body.grid->constTree().cbeginValueOn(); it; ++it) acc.setValueOn(it.getCoord() - origin, 1.0f);
    }
    // FNV-1a over the shifted voxels in the new tree's own (canonical) order.
    uint64_t hash = 1469598103934665603ull;
    for (auto it = tree->cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        for (int32_t v : {c.x(), c.y(), c.z()}) hash = (hash ^ uint32_t(v)) * 1099511628211ull;
    }
    auto [first, last] = mTreesByShape.equal_range(hash);
    for (auto it = first; it != last; ++it)
        if (it->second->hasSameTopology(*tree)) return mSolids.emplace(body.id, Solid{it->second, origin}).first->second;
    mTreesByShape.emplace(hash, tree);
    return mSolids.emplace(body.id, Solid{tree, origin}).first->second;
}

std::string FrameWriter::write(const FrameInfo& info, const std::vector<Body>& bodies)
{
    openvdb::GridPtrVec grids;
    std::unordered_set<int64_t> alive;
    for (const Body& body : bodies) {
        alive.insert(body.id);
        const Solid& solid = solidOf(body);
        auto grid = openvdb::FloatGrid::create(solid.tree);
        auto transform = body.indexToWorld();
        transform->preTranslate(solid.originIjk.asVec3d());
        grid->setTransform(transform);
        grid->setName("fragment_" + std::to_string(body.id));
        grid->setGridClass(openvdb::GRID_FOG_VOLUME);
        grid->insertMeta("frame", openvdb::Int32Metadata(info.frame));
        grid->insertMeta("time_s", openvdb::DoubleMetadata(info.timeS));
        grid->insertMeta("body_id", openvdb::Int64Metadata(body.id));
        grid->insertMeta("parent_id", openvdb::Int64Metadata(body.parentId));
        grid->insertMeta("mass_kg", openvdb::DoubleMetadata(body.mass.massKg));
        grid->insertMeta("voxel_count", openvdb::Int64Metadata(body.mass.voxelCount));
        const auto& v = body.motion.linearVelocityMS;
        const auto& w = body.motion.angularVelocityRadS;
        grid->insertMeta("linear_velocity_m_s", openvdb::Vec3DMetadata(openvdb::Vec3d(v.x(), v.y(), v.z())));
        grid->insertMeta("angular_velocity_rad_s", openvdb::Vec3DMetadata(openvdb::Vec3d(w.x(), w.y(), w.z())));
        const auto& p = body.motion.positionM;
        grid->insertMeta("centre_of_mass_m", openvdb::Vec3DMetadata(openvdb::Vec3d(p.x(), p.y(), p.z())));
        grid->insertMeta("anchored", openvdb::BoolMetadata(body.anchored));
        grids.push_back(grid);
    }
    for (auto it = mSolids.begin(); it != mSolids.end();) it = alive.count(it->first) ? std::next(it) : mSolids.erase(it);
    for (auto it = mTreesByShape.begin(); it != mTreesByShape.end();) it = it->second.use_count() > 1 ? std::next(it) : mTreesByShape.erase(it);
    if (mDensityGrid && !bodies.empty()) {
        auto density = rasteriseDensity(bodies, bodies.front().voxelSizeM);
        density->insertMeta("frame", openvdb::Int32Metadata(info.frame));
        density->insertMeta("time_s", openvdb::DoubleMetadata(info.timeS));
        grids.push_back(density);
    }
    openvdb::MetaMap fileMeta;
    fileMeta.insertMeta("frame", openvdb::Int32Metadata(info.frame));
    fileMeta.insertMeta("time_s", openvdb::DoubleMetadata(info.timeS));
    fileMeta.insertMeta("spall_version", openvdb::StringMetadata(SPALL_VERSION));
    const std::string path = framePath(mDirectory, info.frame);
    writeGridsAtomically(path, grids, fileMeta);
    return path;
}

openvdb::FloatGrid::Ptr rasteriseDensity(const std::vector<Body>& bodies, double h)
{
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setTransform(openvdb::math::Transform::createLinearTransform(h));
    density->setName("density");
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto out = density->getAccessor();
    for (const Body& body : bodies) {
        // Visit world voxels in the body's bounding box and look each one up in the body's own
        // index space: no holes, whatever the rotation.
        const Eigen::Matrix3d toLocal = body.motion.orientation.toRotationMatrix().transpose();
        // World box around the body's index box (its eight corners, voxel cubes included).
        const openvdb::CoordBBox& box = body.indexBounds;
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
        for (int c = 0; c < 8; ++c) {
            const Eigen::Vector3d corner((c & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5),
                                         (c & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5),
                                         (c & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5));
            const Eigen::Vector3d world = body.motion.positionM + body.motion.orientation * (corner * h - body.mass.centreOfMassLocalM);
            lo = lo.cwiseMin(world / h);
            hi = hi.cwiseMax(world / h);
        }
        auto in = body.grid->getConstAccessor();
        for (int i = int(std::floor(lo.x())); i <= int(std::ceil(hi.x())); ++i)
            for (int j = int(std::floor(lo.y())); j <= int(std::ceil(hi.y())); ++j)
                for (int k = int(std::floor(lo.z())); k <= int(std::ceil(hi.z())); ++k) {
                    const Eigen::Vector3d world(i * h, j * h, k * h);
                    const Eigen::Vector3d index = (toLocal * (world - body.motion.positionM) + body.mass.centreOfMassLocalM) / h;
                    const openvdb::Coord ijk(int(std::lround(index.x())), int(std::lround(index.y())), int(std::lround(index.z())));
                    if (in.isValueOn(ijk)) out.setValueOn(openvdb::Coord(i, j, k), 1.0f);
                }
    }
    return density;
}

}  // namespace spall
