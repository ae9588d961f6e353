// Which faces touch air: a face whose neighbouring cell holds a voxel of another body (packed
// fragments, stacked pieces) takes no blast load, and bodies pressed together are loaded as one
// object (one outline, so one clearing time), so a body's impulse does not depend on whether it
// has broken into pieces that still touch.
#pragma once

#include <spall/world/StaticWorld.h>
#include <spall/voxel/Body.h>

#include <Eigen/Core>
#include <tbb/collaborative_call_once.h>

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace spall {

/// The oriented box of a body's voxel cubes, in the world.
ObstacleBox worldBounds(const Body& body);

/// A voxel's free face (no voxel of its body beyond it) whose neighbouring cell's centre lies
/// deepest inside one of the boxes, with that depth (unit: m); face -1 when every such centre
/// lies outside them all. A box holds the voxel across that face (an anchor to a collider).
struct FaceInBox {
    int face = -1;
    double depthM = 0.0;
    int box = -1;  ///< which of the boxes
};
FaceInBox freeFaceDeepestInBoxes(const Body& body, const openvdb::Coord& ijk, const std::vector<ObstacleBox>& boxes);

class Exposure {
public:
    /// Which faces of the bodies `considered` marks are covered, and which bodies are pressed
    /// together. `bodies` must outlive the Exposure: the occupancy of world cells by their
    /// boundary voxels, which a line of sight needs, is built at the first query that needs it
    /// (a wall that is the only body the wave has reached, its faces all on its bounds, never
    /// does), in parallel and sorted (deterministic whatever the thread count).
    Exposure(const std::vector<Body>& bodies, const std::vector<char>& considered);
    Exposure(std::vector<Body>&&, const std::vector<char>&) = delete;  // the bodies must outlive it

    /// True when the cell across exposed face `faceIndex` of the body holds a voxel of another
    /// body (its centre within half a voxel of where a face neighbour's would be).
    bool covered(size_t bodyIndex, size_t faceIndex) const
    {
        return !mCovered[bodyIndex].empty() && mCovered[bodyIndex][faceIndex];
    }

    /// The first considered body (from `fromM`) outside the group `excludeGroup` (kNoBody: none
    /// excluded) with a voxel on the segment from `fromM` to `toM` (world; cells of the voxel
    /// size around voxel centres, sampled every voxel, skipping blocks of 8^3 cells that hold
    /// none), or -1.
    int64_t firstBlocker(const Eigen::Vector3d& fromM, const Eigen::Vector3d& toM, size_t excludeGroup) const;

    /// The bounds of the group of bodies pressed together that a considered body belongs to,
    /// in the world: what the wave goes round. A body alone: its oriented box; a group: the
    /// world-axis box round its members' boxes.
    const ObstacleBox& groupBoundsOf(size_t bodyIndex) const { return mGroupBounds[mGroup[bodyIndex]]; }

    static constexpr size_t kNoBody = ~size_t(0);

    /// Per body: the lowest index of the group of bodies pressed together that it belongs to
    /// (itself when it touches none, or was not considered).
    const std::vector<uint32_t>& groupOf() const { return mGroup; }
    /// Whether a body was considered and touches no other.
    bool alone(size_t bodyIndex) const { return mGroupMembers[mGroup[bodyIndex]] == 1; }

private:
    struct Cell {
        uint64_t key;
        uint32_t body;
        float centre[3];  ///< centre of the voxel in cell units from the lattice origin
    };
    /// The considered bodies' boundary voxels as sorted cells of a lattice through one of them,
    /// their blocks' bits and their bounds.
    void collectCells() const;
    /// The cells, their blocks and the blocks' owners, once, whichever query comes first. The
    /// thread that builds them runs its parallel loops in isolation (a face's task stolen while
    /// it waits there would wait on the build itself); threads that come meanwhile help.
    void needCells() const;
    /// mCovered (faces whose neighbouring cell is another body's) and mGroup (bodies pressed
    /// together), among the bodies `near` marks.
    void groupTouchingBodies(const std::vector<char>& near);
    /// Per body, whether it is considered and another considered body's box comes within two
    /// voxels of its own: only such a body can touch another (a wall alone in the blast has
    /// millions of faces to look across, and nothing to find).
    std::vector<char> nearAnother() const;
    /// mBlocks' occupancy: each cell's bit.
    void markCells() const;
    /// mBlocks' owners: the group of the cells in or next to each block, or kManyGroups.
    void ownBlocks() const;
    /// mGroupBounds from the groups and the members' oriented boxes.
    void boundGroups();
    /// mCellsLo and mCellsHi: the cells' bounds.
    void boundCells() const;
    /// mOnlyGroup and mAnyCells, from the considered bodies' boundary voxels.
    void findOnlyGroup();

    /// World point x in cell units: (x - origin) / h.
    Eigen::Vector3d cellUnits(const Eigen::Vector3d& xM) const { return (xM - mOriginM) / mCellSizeM; }

    const std::vector<Body>& mBodies;
    std::vector<char> mConsidered;
    double mCellSizeM = 1.0;  ///< a cell per voxel: the bodies' voxel size, read from them (unit: m)
    mutable Eigen::Vector3d mOriginM = Eigen::Vector3d::Zero();  ///< a lattice point (unit: m), chosen with the cells
    /// The cells, their blocks and their bounds are built once: by the constructor where bodies
    /// are near one another, else by needCells() from a const query (a cache, hence mutable).
    mutable tbb::collaborative_once_flag mCellsBuilt;
    mutable std::vector<Cell> mCells;  ///< sorted by key, then body
    /// Block owners that are no one group: cells of several groups, and (while the blocks are
    /// built) none yet.
    static constexpr size_t kManyGroups = kNoBody - 1, kUnowned = kNoBody - 2;
    /// A block of 8^3 cells: the one group with cells in or next to it, or kManyGroups; and
    /// which of its cells hold a voxel centre (bit i + 8 j + 64 k of its cell (i, j, k)).
    struct Block {
        size_t owner = kUnowned;
        std::array<uint64_t, 8> occupied{};
    };
    /// Every block holding a cell or next to one.
    mutable std::unordered_map<uint64_t, Block> mBlocks;
    /// The last block looked up: a ray or a face's neighbourhood stays in one block for several
    /// cells, and a hash lookup per cell was a third of a step's loads.
    struct LastBlock {
        uint64_t key = ~uint64_t(0);
        const Block* block = nullptr;
    };
    /// The block of key (null: none), through `last`.
    const Block* findBlock(uint64_t key, LastBlock& last) const;
    /// A body that `skip(body)` does not skip with a voxel that contains x (world, unit: m), or -1.
    template <typename Skip>
    int64_t bodyAt(const Eigen::Vector3d& xM, Skip&& skip, LastBlock& last) const;
    /// Whether any cell from lattice point lo to hi (inclusive, at most one block apart) holds a
    /// voxel centre: a test of bits before bodyAt's search of the sorted cells.
    bool anyOccupied(const int64_t lo[3], const int64_t hi[3], LastBlock& last) const;
    /// Bounds of every cell's centre (cell units), and the group all considered bodies with
    /// boundary voxels belong to when they belong to one (kManyGroups otherwise, found from the
    /// bodies, without the cells): a segment that misses the bounds, or a query that excludes
    /// the only group, meets nothing.
    mutable Eigen::Vector3d mCellsLo = Eigen::Vector3d::Zero(), mCellsHi = Eigen::Vector3d::Zero();
    size_t mOnlyGroup = kManyGroups;
    bool mAnyCells = false;  ///< whether any considered body has a boundary voxel
    std::vector<std::vector<char>> mCovered;  ///< per considered body, per exposed face
    std::vector<uint32_t> mGroup;
    std::vector<uint32_t> mGroupMembers;  ///< per group, at its lowest member's index: its considered bodies
    std::vector<ObstacleBox> mGroupBounds;  ///< per group, at its lowest member's index
};

}  // namespace spall
