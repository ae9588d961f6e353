// A lattice coarser than the body's voxels (lattice.particle_voxels = k > 1): each particle is a
// block of k × k × k voxels, so a body of N voxels steps N / k³ particles at a step k times longer,
// k⁴ times less work, while its pieces keep the voxels' shape. The deformable phase builds its
// lattice from the body's coarsened copy and maps between the two here: faces to particles, a
// fit of particles back to the voxels' body frame.
#pragma once

#include <spall/voxel/Body.h>

#include <cstdint>

namespace spall {

/// The block (a coarse voxel) holding a voxel: floor(ijk / k) per axis.
openvdb::Coord particleCell(const openvdb::Coord& voxel, int particleVoxels);

/// The body as blocks of k³ voxels: a block is in it when any of its voxels is, linked to a
/// neighbouring block when any link joins their voxels, anchored when any of its voxels is;
/// voxels of k h, the same density, placed where the body is, with the body's linear and angular
/// momentum. The blocks' mass is that of whole blocks: exact where the body's outline follows
/// the blocks, heavier by up to a layer of k − 1 voxels over its surface elsewhere, so they move
/// a little slower for the same momentum.
Body coarsenedBody(const Body& body, int particleVoxels);

/// Where a block's centre lies in the body's own frame (index × h), against the coarsened body's
/// frame (index × k h): h (k − 1)/2 along each axis (unit: m).
Eigen::Vector3d blockCentreOffsetM(double voxelSizeM, int particleVoxels);

}  // namespace spall
