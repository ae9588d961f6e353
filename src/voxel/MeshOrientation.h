// Consistent winding for triangle soups: what the winding number and the enclosed volume need.
#pragma once

#include <spall/voxel/Voxelise.h>

#include <cstdint>

namespace spall {

struct MeshTopology {
    int64_t openEdges = 0;          ///< edges used by one triangle, or by more than two
    int64_t turnedTriangles = 0;    ///< triangles whose winding was reversed to agree with their neighbours
    /// Shells inside a closed shell and wound inward: each bounds a hollow (a sealed room).
    int64_t hollows = 0;
    /// Volume inside the outward-wound mesh (unit: m^3): the divergence theorem over each shell,
    /// taken about the shell's vertex mean, so an open shell counts the cone from that point to its
    /// hole; hollows count negative. Exact for closed shells; overlapping shells count their
    /// overlap twice.
    double enclosedVolumeM3 = 0.0;
};

/// Welds vertices at equal positions and drops triangles that collapse, turns triangles so that
/// neighbours across each two-triangle edge wind the same way, then turns each shell that no
/// closed shell holds to face outward. A shell inside another keeps its file's winding: inward,
/// it bounds a hollow (a room sealed inside walls); outward, it is a part inside a part.
MeshTopology orientOutward(TriangleMesh& mesh);

}  // namespace spall
