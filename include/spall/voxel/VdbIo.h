// .vdb output: files are written under a temporary name and renamed when complete, so a file
// that exists is always whole.
#pragma once

#include <spall/voxel/Body.h>

#include <openvdb/openvdb.h>

#include <string>

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


}  // namespace spall
