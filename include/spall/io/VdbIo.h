// .vdb output: files are written under a temporary name and renamed when complete, so a file
// that exists is always whole.
#pragma once

#include <spall/voxel/Body.h>

#include <openvdb/openvdb.h>

#include <string>
#include <unordered_map>
#include <vector>

namespace spall {

/// Calls openvdb::initialize() once (thread-safe).
void initialiseOpenVdb();

/// Writes grids to `path` atomically (temporary name, then rename). Throws IoError.
void writeGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids,
                          const openvdb::MetaMap& fileMetadata = openvdb::MetaMap());

/// Writes a voxelised body: `solid` (FloatGrid, 1 inside, for any reader: vdb_print, pyopenvdb,
/// Blender, Houdini) and `links` (FloatGrid of the link and anchor bits as exact integers, which
/// spall reads back), with metadata
/// voxel_size_m, source, material and spall_version.
void writeVoxelisedBody(const std::string& path, const LinkGrid& grid, double voxelSizeM, const std::string& source,
                        const std::string& material = "unassigned");

/// Reads the `links` grid of a voxelised body file. Throws IoError naming the file.
LinkGrid::Ptr readLinkGrid(const std::string& path);


struct FrameInfo {
    int frame = 0;
    double timeS = 0;
};

/// Writes OUTDIR/fragments.NNNN.vdb: one FloatGrid per body named fragment_<id> (value 1 inside,
/// transform = the body's exact index-to-world map, motion metadata) plus, if asked, a
/// world-space `density` grid with all bodies. Each fragment's tree starts at index (0,0,0)
/// (the offset is in its transform), so fragments of the same shape — debris is full of
/// single voxels — share one tree, which the file stores once (OpenVDB instancing).
class FrameWriter {
public:
    FrameWriter(std::string outputDirectory, bool densityGrid);
    /// Returns the path written.
    std::string write(const FrameInfo& info, const std::vector<Body>& bodies);
    static std::string framePath(const std::string& directory, int frame);

private:
    struct Solid {
        openvdb::FloatTree::Ptr tree;
        openvdb::Coord originIjk;  ///< the tree's (0,0,0) in the body's index space
    };
    const Solid& solidOf(const Body& body);
    std::string mDirectory;
    bool mDensityGrid;
    std::unordered_map<int64_t, Solid> mSolids;                                 ///< per body id
    std::unordered_multimap<uint64_t, openvdb::FloatTree::Ptr> mTreesByShape;  ///< by shape hash
};

/// Rasterises bodies into one world-space grid of voxel size h (value 1 where a voxel centre of
/// the world grid falls inside some body voxel).
openvdb::FloatGrid::Ptr rasteriseDensity(const std::vector<Body>& bodies, double voxelSizeM);

}  // namespace spall
