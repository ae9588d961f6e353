#include "WindingNumber.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace spall {

namespace {

constexpr int kLeafTriangles = 2;
/// A cluster counts as its dipole when the query is farther than this many cluster radii from its
/// centre, the accuracy parameter Barill et al. (2018) use by default. Its error is checked in the
/// tests: zero misclassified centres on a closed tilted box (docs/accuracy.md).
constexpr double kFarFieldRatio = 2.0;
constexpr double kFourPi = 4.0 * M_PI;

/// Solid angle of triangle (a, b, c) seen from the origin, signed by its winding (Van Oosterom and
/// Strackee 1983, "The solid angle of a plane triangle", IEEE Trans. Biomed. Eng. 30(2)).
double solidAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    // In the triangle's plane the angle is 0 beside it and undefined on it: a point on the
    // surface takes only what the rest of the mesh gives, so a lone sheet has no inside.
    if (numerator == 0.0) return 0.0;
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    return 2.0 * std::atan2(numerator, denominator);
}

/// True when the triangle meets the box: no separating axis among the box's three, the
/// triangle's normal and the nine edge-by-axis cross products (the separating axis theorem, as in
/// Akenine-Moeller 2001, "Fast 3D triangle-box overlap testing").
bool triangleMeetsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::AlignedBox3d& box)
{
    const Eigen::Vector3d centre = box.center(), half = 0.5 * box.sizes();
    const Eigen::Vector3d v[3] = {a - centre, b - centre, c - centre};
    const auto separates = [&](const Eigen::Vector3d& axis) {
        const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
        const double reach = half.dot(axis.cwiseAbs());
        return std::min({p0, p1, p2}) > reach || std::max({p0, p1, p2}) < -reach;
    };
    const Eigen::Vector3d edges[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    for (int axis = 0; axis < 3; ++axis) {
        if (separates(Eigen::Vector3d::Unit(axis))) return false;
        for (const auto& edge : edges)
            if (separates(edge.cross(Eigen::Vector3d::Unit(axis)))) return false;
    }
    return !separates(edges[0].cross(edges[1]));
}

Eigen::Vector3d centroid(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) { return (a + b + c) / 3.0; }

}  // namespace

WindingNumberField::WindingNumberField(const TriangleMesh& mesh)
{
    mTriangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles)
        mTriangles.push_back({mesh.positionsM[t[0]].cast<double>(), mesh.positionsM[t[1]].cast<double>(), mesh.positionsM[t[2]].cast<double>()});
    mNodes.reserve(2 * mTriangles.size() / kLeafTriangles + 1);
    if (!mTriangles.empty()) build(0, static_cast<int>(mTriangles.size()));
}

/// Splits at the median centroid along the longest axis of the centroids' bounds.
int WindingNumberField::build(int first, int count)
{
    const int index = static_cast<int>(mNodes.size());
    mNodes.emplace_back();
    mNodes[index].first = first;
    mNodes[index].count = count;
    summarise(mNodes[index]);
    if (count <= kLeafTriangles) return index;
    Eigen::AlignedBox3d centres;
    for (int i = first; i < first + count; ++i) centres.extend(centroid(mTriangles[i].a, mTriangles[i].b, mTriangles[i].c));
    int axis = 0;
    centres.sizes().maxCoeff(&axis);
    const auto begin = mTriangles.begin() + first;
    std::nth_element(begin, begin + count / 2, begin + count, [axis](const Triangle& x, const Triangle& y) {
        return (x.a + x.b + x.c)[axis] < (y.a + y.b + y.c)[axis];
    });
    const int left = build(first, count / 2);
    const int right = build(first + count / 2, count - count / 2);
    mNodes[index].left = left;
    mNodes[index].right = right;
    return index;
}

void WindingNumberField::summarise(Node& node) const
{
    double area = 0.0;
    Eigen::Vector3d weighted = Eigen::Vector3d::Zero();
    node.areaNormalM2.setZero();
    for (int i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = mTriangles[i];
        const Eigen::Vector3d doubleAreaNormal = (t.b - t.a).cross(t.c - t.a);
        const double triangleArea = 0.5 * doubleAreaNormal.norm();
        node.areaNormalM2 += 0.5 * doubleAreaNormal;
        weighted += triangleArea * centroid(t.a, t.b, t.c);
        area += triangleArea;
        node.bounds.extend(t.a);
        node.bounds.extend(t.b);
        node.bounds.extend(t.c);
    }
    node.centreM = area > 0.0 ? Eigen::Vector3d(weighted / area) : node.bounds.center();
    for (int i = node.first; i < node.first + node.count; ++i)
        for (const Eigen::Vector3d* v : {&mTriangles[i].a, &mTriangles[i].b, &mTriangles[i].c})
            node.radiusM = std::max(node.radiusM, (*v - node.centreM).norm());
}

double WindingNumberField::at(const Eigen::Vector3d& q) const
{
    if (mNodes.empty()) return 0.0;
    double turns = 0.0;
    int stack[128];
    int depth = 0;
    stack[depth++] = 0;
    while (depth > 0) {
        const Node& node = mNodes[stack[--depth]];
        const Eigen::Vector3d toCentre = node.centreM - q;
        const double distance = toCentre.norm();
        if (distance > kFarFieldRatio * node.radiusM) {
            // Dipole term of the cluster (Barill et al. 2018, eq. 7 to first order).
            turns += node.areaNormalM2.dot(toCentre) / (kFourPi * distance * distance * distance);
        } else if (node.left < 0) {
            for (int i = node.first; i < node.first + node.count; ++i)
                turns += solidAngle(mTriangles[i].a - q, mTriangles[i].b - q, mTriangles[i].c - q) / kFourPi;
        } else {
            stack[depth++] = node.left;
            stack[depth++] = node.right;
        }
    }
    return turns;
}

bool WindingNumberField::anyTriangleMeets(const Eigen::AlignedBox3d& box) const
{
    if (mNodes.empty()) return false;
    int stack[128];
    int depth = 0;
    stack[depth++] = 0;
    while (depth > 0) {
        const Node& node = mNodes[stack[--depth]];
        if (!node.bounds.intersects(box)) continue;
        if (node.left >= 0) {
            stack[depth++] = node.left;
            stack[depth++] = node.right;
            continue;
        }
        for (int i = node.first; i < node.first + node.count; ++i)
            if (triangleMeetsBox(mTriangles[i].a, mTriangles[i].b, mTriangles[i].c, box)) return true;
    }
    return false;
}

namespace {

constexpr int kBlock = LinkLeaf::DIM;  // one OpenVDB leaf per block
using BlockMask = std::array<uint64_t, kBlock * kBlock * kBlock / 64>;

void setInside(BlockMask& mask, const openvdb::Coord& local)
{
    const int n = static_cast<int>(LinkLeaf::coordToOffset(local));
    mask[n / 64] |= uint64_t(1) << (n % 64);
}

/// Marks the inside voxels of the cube of `size` voxels at `local` (in the block at `blockOrigin`).
/// A cube that no triangle meets, and whose corners and centre agree, is
/// all inside or all outside: away from the surface the winding number is harmonic (constant for a
/// closed mesh), so its one-half level cannot close on itself inside the cube. Otherwise the cube
/// splits into eight, down to single voxels, so only voxels near the surface are evaluated one by one.
void classifyCube(const WindingNumberField& field, const openvdb::Coord& blockOrigin, const openvdb::Coord& local, int size,
                  double h, BlockMask& mask)
{
    const openvdb::Coord first = blockOrigin + local;
    const Eigen::Vector3d firstM = Eigen::Vector3d(first.x(), first.y(), first.z()) * h;
    if (size == 1) {
        if (field.at(firstM) > 0.5) setInside(mask, local);
        return;
    }
    const double spanM = (size - 1) * h;
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.5 * h);  // the voxels' own cubes
    if (!field.anyTriangleMeets(Eigen::AlignedBox3d(firstM - margin, firstM + Eigen::Vector3d::Constant(spanM) + margin))) {
        const bool centreInside = field.at(firstM + Eigen::Vector3d::Constant(0.5 * spanM)) > 0.5;
        bool agree = true;
        for (int corner = 0; corner < 8 && agree; ++corner) {
            const Eigen::Vector3d offset(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            agree = (field.at(firstM + spanM * offset) > 0.5) == centreInside;
        }
        if (agree) {
            if (centreInside)
                for (int i = 0; i < size; ++i)
                    for (int j = 0; j < size; ++j)
                        for (int k = 0; k < size; ++k) setInside(mask, local + openvdb::Coord(i, j, k));
            return;
        }
    }
    const int half = size / 2;
    for (int child = 0; child < 8; ++child)
        classifyCube(field, blockOrigin, local + openvdb::Coord((child & 1) * half, ((child >> 1) & 1) * half, ((child >> 2) & 1) * half),
                     half, h, mask);
}

}  // namespace

void fillWindingNumberInterior(const TriangleMesh& mesh, LinkGrid& solid, const std::string& sourceName, Interrupter* interrupter)
{
    const double h = solid.voxelSize()[0];
    const WindingNumberField field(mesh);
    Eigen::AlignedBox3d bounds;
    for (const auto& p : mesh.positionsM) bounds.extend(p.cast<double>());
    std::vector<openvdb::Coord> origins;
    const auto blockOf = [h](double x) { return static_cast<int>(std::floor(std::floor(x / h) / kBlock)) * kBlock; };
    for (int i = blockOf(bounds.min().x()); i <= blockOf(bounds.max().x()) + kBlock; i += kBlock)
        for (int j = blockOf(bounds.min().y()); j <= blockOf(bounds.max().y()) + kBlock; j += kBlock)
            for (int k = blockOf(bounds.min().z()); k <= blockOf(bounds.max().z()) + kBlock; k += kBlock) origins.emplace_back(i, j, k);

    std::vector<BlockMask> masks(origins.size());
    constexpr size_t kBlocksPerReport = 128;  // well under a second between checks for Ctrl-C
    for (size_t begin = 0; begin < origins.size(); begin += kBlocksPerReport) {
        const size_t end = std::min(origins.size(), begin + kBlocksPerReport);
        tbb::parallel_for(tbb::blocked_range<size_t>(begin, end), [&](const tbb::blocked_range<size_t>& range) {
            for (size_t b = range.begin(); b != range.end(); ++b) classifyCube(field, origins[b], openvdb::Coord(0), kBlock, h, masks[b]);
        });
        if (interrupter && interrupter->wasInterrupted(static_cast<int>(100 * end / origins.size())))
            throw VoxeliseInterrupted(sourceName + ": voxelising was interrupted");
    }
    for (size_t b = 0; b < origins.size(); ++b) {
        if (std::all_of(masks[b].begin(), masks[b].end(), [](uint64_t word) { return word == 0; })) continue;
        LinkLeaf* leaf = solid.tree().touchLeaf(origins[b]);
        for (int n = 0; n < kBlock * kBlock * kBlock; ++n)
            if (masks[b][n / 64] >> (n % 64) & 1) leaf->setValueOn(n, 0);
    }
}

}  // namespace spall
