#include <spall/voxel/VdbIo.h>

#include <spall/core/AtomicFile.h>

#include <spall/core/Error.h>

#include <openvdb/io/Archive.h>
#include <openvdb/io/File.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <unistd.h>

namespace spall {

void initialiseOpenVdb()
{
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        // spall's own tree shapes, so checkpoints can stream them.
        if (!LinkGrid::isRegistered()) LinkGrid::registerGrid();
        if (!DamageGrid::isRegistered()) DamageGrid::registerGrid();
        if (!LinkDamageGrid::isRegistered()) LinkDamageGrid::registerGrid();
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


}  // namespace spall
