// The layout of a voxel's value in a body's link grid, in one place: bits 0-5 the links to the
// six face neighbours (kept symmetric), bit 6 the anchor (a bond to the world), bits 8-25 the
// weakening state of the +x, +y and +z links (fracture algorithm 2), bits 26-31 the links that
// broke (so a face is known to be fracture surface, not the object's own). Kept in the link grid
// because it is the links' own state, and so it follows a voxel through every split for free.
#pragma once

#include <openvdb/openvdb.h>

#include <Eigen/Core>

#include <cstdint>

namespace spall {

/// Face (and link) directions: bit f of a voxel's value is the link across face f.
enum Face : int { kNegX = 0, kPosX = 1, kNegY = 2, kPosY = 3, kNegZ = 4, kPosZ = 5 };
inline constexpr int kFaceCount = 6;
inline constexpr int32_t kAllLinks = 0x3f;
/// Bond to the world (an anchor); a body holding any anchored voxel is static.
inline constexpr int32_t kAnchorBit = 0x40;

inline int oppositeFace(int face) { return face ^ 1; }
inline int faceAxis(int face) { return face >> 1; }
inline int faceSign(int face) { return (face & 1) ? 1 : -1; }
inline openvdb::Coord faceOffset(int face)
{
    openvdb::Coord c(0, 0, 0);
    c[faceAxis(face)] = faceSign(face);
    return c;
}
inline Eigen::Vector3d faceNormal(int face)
{
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[faceAxis(face)] = faceSign(face);
    return n;
}

/// Bits 8..25: for each +x, +y, +z link, 1 + the index of the charge that first loaded it
/// beyond its weakened limit (0: never); six bits each.
inline constexpr int kWeakenedShift = 8;
inline constexpr int kWeakenedBits = 6;
inline constexpr int kWeakenedMask = (1 << kWeakenedBits) - 1;
/// The most charges (ground images included) fracture algorithm 2 can tell apart.
inline constexpr int kMaxWeakeningCharges = kWeakenedMask - 1;
inline int weakenedByCharge(int32_t bits, int axis) { return ((bits >> (kWeakenedShift + kWeakenedBits * axis)) & kWeakenedMask) - 1; }
inline int32_t withWeakenedByCharge(int32_t bits, int axis, int charge)
{
    const int shift = kWeakenedShift + kWeakenedBits * axis;
    return (bits & ~(kWeakenedMask << shift)) | (((charge + 1) & kWeakenedMask) << shift);
}

/// Bits 26..31: bit 26 + f is set once the link across face f has broken.
inline constexpr int kBrokenShift = 26;
inline int brokenFaceBits(int32_t bits) { return static_cast<int>((static_cast<uint32_t>(bits) >> kBrokenShift) & kAllLinks); }
inline int32_t withBrokenFace(int32_t bits, int face)
{
    return static_cast<int32_t>(static_cast<uint32_t>(bits) | (uint32_t(1) << (kBrokenShift + face)));
}

}  // namespace spall
