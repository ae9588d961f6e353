// A lattice coarser than the body's voxels (lattice.particle_voxels = k > 1): each particle is a
// block of k × k × k voxels, so a body of N voxels steps N / k³ particles at a step k times longer,
// k⁴ times less work, while its pieces keep the voxels' shape. The deformable phase builds its
// lattice from the body's coarsened copy and maps between the two here: faces to particles, a
// fit of particles back to the voxels' body frame.
#pragma once

#include <spall/voxel/Body.h>
#include <spall/voxel/LinkBits.h>

#include <cstdint>

namespace spall {

/// How a body's voxels make a lattice's particles: blocks of k³ voxels, counted from `origin`
/// (the low corner of the body's voxels when it entered the phase, so a wall's lowest blocks sit
/// on the ground as its voxels do; its parts keep the whole's blocks). k = 1: a particle per voxel.
struct VoxelBlocks {
    int voxels = 1;
    openvdb::Coord origin{0};
};

/// The blocks a body entering the phase is cut into (settings' lattice.particle_voxels).
VoxelBlocks blocksFor(const Body& body, int particleVoxels);

/// The block (the coarsened body's voxel) holding a voxel: floor((ijk − origin) / k) per axis.
openvdb::Coord particleCell(const openvdb::Coord& voxel, const VoxelBlocks& blocks);

/// f(voxel) for the cells of a block (voxels of the body or not): all k³ of them, or with
/// `face` >= 0 the k² on that face.
template <typename F>
void forEachCellOfBlock(const openvdb::Coord& block, const VoxelBlocks& blocks, int face, F&& f)
{
    const int k = blocks.voxels;
    openvdb::Coord low = openvdb::Coord(block.x() * k, block.y() * k, block.z() * k) + blocks.origin;
    openvdb::Coord high = low.offsetBy(k - 1);
    if (face >= 0) {
        const int axis = faceAxis(face);
        low[axis] = high[axis] = faceSign(face) > 0 ? high[axis] : low[axis];
    }
    for (int x = low.x(); x <= high.x(); ++x)
        for (int y = low.y(); y <= high.y(); ++y)
            for (int z = low.z(); z <= high.z(); ++z) f(openvdb::Coord(x, y, z));
}

/// The body as blocks of k³ voxels: a block is in it when any of its voxels is, linked to a
/// neighbouring block when any link joins their voxels, anchored when any of its voxels is;
/// voxels of k h placed where the body is, moving with its velocity field. Blocks at the surface
/// are partly empty, so the blocks share the body's mass evenly (their density is the body's
/// times the fraction of their cells it fills): the lattice weighs what the body does and takes
/// the same loads at the same acceleration. A block of few voxels moves as heavier than they are
/// (mass scaling: its own voxels' mass would shorten the stable step by the root of its fill).
Body coarsenedBody(const Body& body, const VoxelBlocks& blocks);

/// Where a block's centre lies in the body's own frame (index × h), against the coarsened body's
/// frame (index × k h): h (origin + (k − 1)/2) (unit: m).
Eigen::Vector3d blockCentreOffsetM(double voxelSizeM, const VoxelBlocks& blocks);

}  // namespace spall
