#include <spall/lattice/ParticleBlocks.h>

#include <spall/core/IntegerMath.h>
#include <spall/voxel/LinkBits.h>

namespace spall {

VoxelBlocks blocksFor(const Body& body, int particleVoxels)
{
    if (particleVoxels == 1) return VoxelBlocks();
    return {particleVoxels, body.indexBounds.min()};
}

openvdb::Coord particleCell(const openvdb::Coord& voxel, const VoxelBlocks& blocks)
{
    const int k = blocks.voxels;
    if (k == 1) return voxel;
    const openvdb::Coord v = voxel - blocks.origin;
    return {floorDivide(v.x(), k), floorDivide(v.y(), k), floorDivide(v.z(), k)};
}

Eigen::Vector3d blockCentreOffsetM(double voxelSizeM, const VoxelBlocks& blocks)
{
    const openvdb::Coord& o = blocks.origin;
    return voxelSizeM * (Eigen::Vector3d(o.x(), o.y(), o.z()) + Eigen::Vector3d::Constant(0.5 * (blocks.voxels - 1)));
}

Body coarsenedBody(const Body& body, const VoxelBlocks& blocks)
{
    const int k = blocks.voxels;
    Body coarse;
    coarse.id = body.id;
    coarse.parentId = body.parentId;
    coarse.materialIndex = body.materialIndex;
    coarse.voxelSizeM = k * body.voxelSizeM;
    coarse.grid = LinkGrid::create(0);
    auto cells = coarse.grid->getAccessor();
    for (auto it = body.grid->constTree().cbeginValueOn(); it; ++it) {
        const openvdb::Coord voxel = it.getCoord();
        const openvdb::Coord block = particleCell(voxel, blocks);
        int32_t bits = cells.isValueOn(block) ? cells.getValue(block) : 0;
        bits |= *it & kAnchorBit;
        // A link from a voxel into another block is a link between the blocks (both voxels see
        // it, so the blocks' links stay symmetric).
        for (int face = 0; face < kFaceCount; ++face)
            if ((*it & (1 << face)) && particleCell(voxel + faceOffset(face), blocks) != block) bits |= 1 << face;
        cells.setValueOn(block, bits);
    }
    // The blocks share the body's mass: its density times the fraction of their cells it fills.
    const int64_t blockCells = int64_t(k) * k * k * int64_t(coarse.grid->activeVoxelCount());
    coarse.densityKgM3 = body.densityKgM3 * double(body.grid->activeVoxelCount()) / double(blockCells);
    refreshDerivedData(coarse);
    // Placed where the body's motion puts the blocks, moving as the body's points there move, so
    // a lattice that does not deform gives the body back exactly its motion (setMotionsFromFit).
    const Eigen::Vector3d shift = body.motion.orientation *
                                  (coarse.mass.centreOfMassLocalM + blockCentreOffsetM(body.voxelSizeM, blocks) - body.mass.centreOfMassLocalM);
    coarse.motion = body.motion;
    coarse.motion.positionM = body.motion.positionM + shift;
    coarse.motion.linearVelocityMS = body.motion.linearVelocityMS + body.motion.angularVelocityRadS.cross(shift);
    return coarse;
}

}  // namespace spall
