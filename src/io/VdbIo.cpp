#include <spall/io/VdbIo.h>

#include <spall/core/Error.h>

#include <openvdb/io/File.h>

#include <cstdio>
#include <filesystem>
#include <mutex>
#include <unistd.h>

namespace spall {

void initialiseOpenVdb()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

void writeGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& fileMetadata)
{
    initialiseOpenVdb();
    const std::string temporary = path + ".partial." + std::to_string(::getpid());
    try {
        openvdb::io::File file(temporary);
        file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write(grids, fileMetadata);
        file.close();
    } catch (const std::exception& e) {
        std::error_code ec;
        std::filesystem::remove(temporary, ec);
        throw IoError(path + ": cannot write: " + e.what());
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
        std::filesystem::remove(temporary, ec);
        throw IoError(path + ": cannot rename the finished file into place: " + ec.message());
    }
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
            if (auto link = openvdb::gridPtrCast<LinkGrid>(g)) return link;
        }
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read as .vdb: " + e.what());
    }
    throw IoError(path + ": holds no Int32 solid grid");
}

}  // namespace spall
