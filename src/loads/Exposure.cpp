#include <spall/loads/Exposure.h>

#include <spall/core/DisjointSets.h>
#include <spall/core/Parallel.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>
#include <cmath>

namespace spall {

namespace {

/// Cell of lattice point (i, j, k), 21 bits per axis (+-10^6 cells).
uint64_t cellKey(int64_t i, int64_t j, int64_t k)
{
    auto axis = [](int64_t v) { return uint64_t(v + (int64_t(1) << 20)) & 0x1fffff; };
    return (axis(i) << 42) | (axis(j) << 21) | axis(k);
}

constexpr int kBlockShift = 3;  ///< blocks of 8^3 cells

uint64_t blockKey(int64_t i, int64_t j, int64_t k) { return cellKey(i >> kBlockShift, j >> kBlockShift, k >> kBlockShift); }

/// Cell of a point in cell units: the nearest lattice point.
uint64_t cellKey(const Eigen::Vector3d& u) { return cellKey(std::llround(u.x()), std::llround(u.y()), std::llround(u.z())); }

}  // namespace

ObstacleBox worldBounds(const Body& body)
{
    const openvdb::CoordBBox& box = body.indexBounds;
    const Eigen::Vector3d lo(box.min().x(), box.min().y(), box.min().z()), hi(box.max().x(), box.max().y(), box.max().z());
    ObstacleBox out;
    out.orientation = body.motion.orientation;
    out.centreM = body.motion.positionM + body.motion.orientation * (0.5 * (lo + hi) * body.voxelSizeM - body.mass.centreOfMassLocalM);
    out.halfExtentM = (0.5 * (hi - lo) + Eigen::Vector3d::Constant(0.5)) * body.voxelSizeM;
    return out;
}

FaceInBox freeFaceDeepestInBoxes(const Body& body, const openvdb::Coord& ijk, const std::vector<ObstacleBox>& boxes)
{
    FaceInBox deepest{-1, -std::numeric_limits<double>::infinity()};
    for (int face = 0; face < 6; ++face) {
        if (body.grid->tree().isValueOn(ijk + faceOffset(face))) continue;
        const Eigen::Vector3d beyondM = body.voxelWorldM(ijk + faceOffset(face));
        for (size_t box = 0; box < boxes.size(); ++box) {
            const double depthM = depthInsideM(boxes[box], beyondM);
            if (depthM > deepest.depthM) deepest = {face, depthM, int(box)};
        }
    }
    return deepest.depthM >= 0.0 ? deepest : FaceInBox();
}

Exposure::Exposure(const std::vector<Body>& bodies, const std::vector<char>& considered)
    : mBodies(bodies), mConsidered(considered), mCovered(bodies.size()), mGroup(bodies.size()), mGroupBounds(bodies.size())
{
    if (bodies.empty()) return;
    mCellSizeM = bodies.front().voxelSizeM;
    // Bodies near no other are each a group of their own, and need no cells to say so.
    for (size_t b = 0; b < bodies.size(); ++b) mGroup[b] = uint32_t(b);
    const std::vector<char> near = nearAnother();
    if (std::find(near.begin(), near.end(), 1) != near.end()) {
        tbb::collaborative_call_once(mCellsBuilt, [&] {
            collectCells();
            groupTouchingBodies(near);  // reads the cells' bits
            ownBlocks();
        });
    }
    boundGroups();
    findOnlyGroup();
}

void Exposure::needCells() const
{
    tbb::collaborative_call_once(mCellsBuilt, [&] {
        collectCells();
        ownBlocks();
    });
}

void Exposure::collectCells() const
{
    const std::vector<Body>& bodies = mBodies;
    const std::vector<char>& considered = mConsidered;
    // The lattice goes through a voxel centre of the first body considered: the pieces of one
    // object then sit on it exactly, and each lookup is a single cell.
    for (size_t b = 0; b < bodies.size(); ++b)
        if (considered[b] && !bodies[b].boundaryVoxels.empty()) {
            mOriginM = bodies[b].voxelWorldM(bodies[b].boundaryVoxels.front());
            break;
        }
    // Every considered body's boundary voxels into one sorted list of cells, each body's at its
    // own offset, in parallel over all of them (a wall's hundreds of thousands too).
    std::vector<size_t> firstCell(bodies.size() + 1, 0);
    for (size_t b = 0; b < bodies.size(); ++b) firstCell[b + 1] = firstCell[b] + (considered[b] ? bodies[b].boundaryVoxels.size() : 0);
    mCells.resize(firstCell.back());
    forEachIndex(
        mCells.size(),
        [&](size_t i) {
            const size_t b = size_t(std::upper_bound(firstCell.begin(), firstCell.end(), i) - firstCell.begin()) - 1;
            const Eigen::Vector3d u = cellUnits(bodies[b].voxelWorldM(bodies[b].boundaryVoxels[i - firstCell[b]]));
            mCells[i] = {cellKey(u), uint32_t(b), {float(u.x()), float(u.y()), float(u.z())}};
        },
        kCheapGrain);
    std::sort(mCells.begin(), mCells.end(), [](const Cell& a, const Cell& c) { return a.key != c.key ? a.key < c.key : a.body < c.body; });
    markCells();
    boundCells();
}

std::vector<char> Exposure::nearAnother() const
{
    const std::vector<Body>& bodies = mBodies;
    const std::vector<char>& considered = mConsidered;
    // The world-axis boxes round the bodies' oriented boxes, swept along x.
    std::vector<Eigen::AlignedBox3d> bounds(bodies.size());
    std::vector<uint32_t> order;
    for (size_t b = 0; b < bodies.size(); ++b) {
        if (!considered[b]) continue;
        for (const Eigen::Vector3d& corner : cornersOf(worldBounds(bodies[b]))) bounds[b].extend(corner);
        order.push_back(uint32_t(b));
    }
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t c) { return bounds[a].min().x() < bounds[c].min().x(); });
    // The point across a face lies within half the body's voxel of its box along each world
    // axis, and bodyAt takes a voxel whose centre is under half a cell from it along each axis,
    // a centre inside its own body's box: boxes more than two cells apart share no face (the
    // bodies of a simulation share the scene's voxel size, the cells').
    const double reachM = 2.0 * mCellSizeM;
    std::vector<char> near(bodies.size(), 0);
    for (size_t i = 0; i < order.size(); ++i) {
        const Eigen::AlignedBox3d grown(bounds[order[i]].min().array() - reachM, bounds[order[i]].max().array() + reachM);
        for (size_t j = i + 1; j < order.size() && bounds[order[j]].min().x() <= grown.max().x(); ++j)
            if (grown.intersects(bounds[order[j]])) near[order[i]] = near[order[j]] = 1;
    }
    return near;
}

void Exposure::groupTouchingBodies(const std::vector<char>& near)
{
    // Per face of a body near another: is the cell across it another body's?
    const std::vector<Body>& bodies = mBodies;
    std::vector<std::vector<uint32_t>> touching(bodies.size());
    forEachIndex(bodies.size(), [&](size_t b) {
        if (!near[b]) return;
        const Body& body = bodies[b];
        const Eigen::Matrix3d rot = body.motion.orientation.toRotationMatrix();
        mCovered[b].assign(body.exposedFaces.size(), 0);
        LastBlock last;
        for (size_t f = 0; f < body.exposedFaces.size(); ++f) {
            const ExposedFace& face = body.exposedFaces[f];
            const Eigen::Vector3d across = body.voxelWorldM(face.voxel) + body.voxelSizeM * (rot * faceNormal(face.face));
            const int64_t other = bodyAt(across, [b](size_t body) { return body == b; }, last);
            if (other < 0) continue;
            mCovered[b][f] = 1;
            touching[b].push_back(uint32_t(other));
        }
    });
    // Groups of bodies pressed together, each named by its lowest index.
    DisjointSets groups(bodies.size());
    for (size_t b = 0; b < bodies.size(); ++b)
        for (uint32_t other : touching[b]) groups.join(uint32_t(b), other);
    for (size_t b = 0; b < bodies.size(); ++b) mGroup[b] = groups.root(uint32_t(b));
}

void Exposure::markCells() const
{
    for (const Cell& c : mCells) {
        const int64_t i = std::llround(c.centre[0]), j = std::llround(c.centre[1]), k = std::llround(c.centre[2]);
        const int bit = int(i & 7) + 8 * int(j & 7) + 64 * int(k & 7);
        mBlocks[blockKey(i, j, k)].occupied[size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
    }
}

void Exposure::ownBlocks() const
{
    // Blocks hold their cells and those next to them: a voxel can contain points of the
    // neighbouring cells (bodies need not share the world's lattice). One of the eight
    // corners is the cell's own block, so every marked block gets an owner. Cells in key order
    // mostly share their corners' blocks with the cell before (the map's nodes stay put).
    std::array<uint64_t, 8> lastKey;
    std::array<Block*, 8> lastBlock{};
    lastKey.fill(~uint64_t(0));
    for (const Cell& c : mCells) {
        const int64_t i = std::llround(c.centre[0]), j = std::llround(c.centre[1]), k = std::llround(c.centre[2]);
        const size_t group = mGroup[c.body];
        for (int corner = 0; corner < 8; ++corner) {
            const uint64_t key = blockKey(i + (corner & 1 ? 1 : -1), j + (corner & 2 ? 1 : -1), k + (corner & 4 ? 1 : -1));
            if (key != lastKey[size_t(corner)]) lastKey[size_t(corner)] = key, lastBlock[size_t(corner)] = &mBlocks[key];
            Block& block = *lastBlock[size_t(corner)];
            if (block.owner == kUnowned)
                block.owner = group;
            else if (block.owner != group)
                block.owner = kManyGroups;
        }
    }
}

void Exposure::boundCells() const
{
    if (mCells.empty()) return;
    mCellsLo = mCellsHi = Eigen::Vector3d(mCells.front().centre[0], mCells.front().centre[1], mCells.front().centre[2]);
    for (const Cell& c : mCells) {
        const Eigen::Vector3d u(c.centre[0], c.centre[1], c.centre[2]);
        mCellsLo = mCellsLo.cwiseMin(u);
        mCellsHi = mCellsHi.cwiseMax(u);
    }
}

void Exposure::findOnlyGroup()
{
    for (size_t b = 0; b < mBodies.size(); ++b) {
        if (!mConsidered[b] || mBodies[b].boundaryVoxels.empty()) continue;
        if (!mAnyCells)
            mOnlyGroup = mGroup[b];
        else if (mGroup[b] != mOnlyGroup)
            mOnlyGroup = kManyGroups;
        mAnyCells = true;
    }
}

void Exposure::boundGroups()
{
    const std::vector<Body>& bodies = mBodies;
    const std::vector<char>& considered = mConsidered;
    mGroupMembers.assign(bodies.size(), 0);
    for (size_t b = 0; b < bodies.size(); ++b)
        if (considered[b]) ++mGroupMembers[mGroup[b]];
    const std::vector<uint32_t>& members = mGroupMembers;
    std::vector<Eigen::Vector3d> lo(bodies.size(), Eigen::Vector3d::Constant(1e300)), hi(bodies.size(), Eigen::Vector3d::Constant(-1e300));
    for (size_t b = 0; b < bodies.size(); ++b) {
        if (!considered[b]) continue;
        const ObstacleBox box = worldBounds(bodies[b]);
        const size_t g = mGroup[b];
        if (members[g] == 1) {
            mGroupBounds[g] = box;
            continue;
        }
        for (const Eigen::Vector3d& corner : cornersOf(box)) lo[g] = lo[g].cwiseMin(corner), hi[g] = hi[g].cwiseMax(corner);
    }
    for (size_t g = 0; g < bodies.size(); ++g)
        if (members[g] > 1) mGroupBounds[g] = {0.5 * (lo[g] + hi[g]), 0.5 * (hi[g] - lo[g]), Eigen::Quaterniond::Identity()};
}

int64_t Exposure::firstBlocker(const Eigen::Vector3d& fromM, const Eigen::Vector3d& toM, size_t excludeGroup) const
{
    const double h = mCellSizeM, length = (toM - fromM).norm();
    if (!mAnyCells || !(length > 0) || excludeGroup == mOnlyGroup) return -1;
    needCells();
    const Eigen::Vector3d dir = (toM - fromM) / length;
    // Slab test of the segment against the cells' bounds, a cell wider all round: a segment
    // that misses them meets no voxel.
    double enter = 0.0, leave = length;
    const Eigen::Vector3d from = cellUnits(fromM);
    for (int a = 0; a < 3; ++a) {
        const double lo = mCellsLo[a] - 1.0, hi = mCellsHi[a] + 1.0, speed = dir[a] / h;  // cell units per metre
        if (speed == 0.0) {
            if (from[a] < lo || from[a] > hi) return -1;
            continue;
        }
        const double t0 = (lo - from[a]) / speed, t1 = (hi - from[a]) / speed;
        enter = std::max(enter, std::min(t0, t1));
        leave = std::min(leave, std::max(t0, t1));
    }
    if (enter > leave) return -1;
    const double blockM = h * (1 << kBlockShift);
    LastBlock lastOnRay, lastAround;
    for (double t = 0; t < length;) {
        const Eigen::Vector3d x = fromM + t * dir, u = cellUnits(x);
        const int64_t i = std::llround(u.x()), j = std::llround(u.y()), k = std::llround(u.z());
        // A block holding only cells of the excluded group is passed like an empty one.
        const Block* block = findBlock(blockKey(i, j, k), lastOnRay);
        if (block && block->owner != excludeGroup) {
            if (const int64_t body = bodyAt(x, [&](size_t b) { return mGroup[b] == excludeGroup; }, lastAround); body >= 0) return body;
            t += h;
            continue;
        }
        // An empty block: go on from where the ray leaves it (its cells span lattice points
        // lo..lo+7, so its faces lie half a cell outside them).
        double exit = 1e300;
        const int64_t index[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
            if (dir[a] == 0) continue;
            const int64_t lo = index[a] & ~int64_t((1 << kBlockShift) - 1);  // down to the block's first cell (no shift of a negative: UB before C++20)
            const double face = dir[a] > 0 ? lo + (1 << kBlockShift) - 0.5 : lo - 0.5;  // in cell units
            exit = std::min(exit, (face - u[a]) * h / dir[a]);
        }
        t += std::max(exit, 0.0) + 1e-6 * blockM;
    }
    return -1;
}

const Exposure::Block* Exposure::findBlock(uint64_t key, LastBlock& last) const
{
    if (key != last.key) {
        const auto it = mBlocks.find(key);
        last = {key, it == mBlocks.end() ? nullptr : &it->second};
    }
    return last.block;
}

bool Exposure::anyOccupied(const int64_t lo[3], const int64_t hi[3], LastBlock& last) const
{
    for (int64_t i = lo[0]; i <= hi[0]; ++i)
        for (int64_t j = lo[1]; j <= hi[1]; ++j)
            for (int64_t k = lo[2]; k <= hi[2]; ++k) {
                const Block* block = findBlock(blockKey(i, j, k), last);
                const int bit = int(i & 7) + 8 * int(j & 7) + 64 * int(k & 7);
                if (block && (block->occupied[size_t(bit >> 6)] >> (bit & 63) & 1)) return true;
            }
    return false;
}

template <typename Skip>
int64_t Exposure::bodyAt(const Eigen::Vector3d& xM, Skip&& skip, LastBlock& last) const
{
    // A voxel within half a cell of x may sit in the next cell along an axis where x lies near
    // a cell boundary (bodies from different objects need not share a lattice): look there too.
    const Eigen::Vector3d u = cellUnits(xM);
    int64_t range[3][2];
    for (int a = 0; a < 3; ++a) {
        const double v = u[a], nearest = std::round(v);
        range[a][0] = range[a][1] = int64_t(nearest);
        if (std::abs(v - nearest) > 0.2) (v > nearest ? range[a][1] : range[a][0]) += v > nearest ? 1 : -1;
    }
    const int64_t lo[3] = {range[0][0], range[1][0], range[2][0]}, hi[3] = {range[0][1], range[1][1], range[2][1]};
    if (!anyOccupied(lo, hi, last)) return -1;
    for (int64_t i = range[0][0]; i <= range[0][1]; ++i)
        for (int64_t j = range[1][0]; j <= range[1][1]; ++j)
            for (int64_t k = range[2][0]; k <= range[2][1]; ++k) {
                const uint64_t key = cellKey(i, j, k);
                auto it = std::lower_bound(mCells.begin(), mCells.end(), key, [](const Cell& c, uint64_t x) { return c.key < x; });
                for (; it != mCells.end() && it->key == key; ++it) {
                    if (skip(it->body)) continue;
                    const double d = std::max({std::abs(it->centre[0] - u.x()), std::abs(it->centre[1] - u.y()), std::abs(it->centre[2] - u.z())});
                    if (d < 0.5) return it->body;
                }
            }
    return -1;
}

}  // namespace spall
