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

/// Reads the first Int32 grid of a voxelised body file. Throws IoError naming the file.
LinkGrid::Ptr readLinkGrid(const std::string& path);

}  // namespace spall
