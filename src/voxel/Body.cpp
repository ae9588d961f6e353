#include <spall/voxel/Body.h>

#include <spall/core/Error.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <sstream>

namespace spall {

namespace {

using LeafManager = openvdb::tree::LeafManager<LinkTree>;
using ConstLeafManager = openvdb::tree::LeafManager<const LinkTree>;

}  // namespace

openvdb::math::Transform::Ptr Body::indexToWorld() const
{
    // world = p + R (h * index - c); OpenVDB maps row vectors: world = index * M.
    const Eigen::Matrix3d r = motion.orientation.toRotationMatrix();
    const Eigen::Vector3d t = motion.positionM - r * mass.centreOfMassLocalM;
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m(i, j) = voxelSizeM * r(j, i);
        m(3, i) = t[i];
    }
    return openvdb::math::Transform::createLinearTransform(m);
}

void linkAllNeighbours(LinkGrid& grid)
{
    // Reads topology through a const accessor per task and writes only the task's own leaf.
    LeafManager leaves(grid.tree());
    const LinkTree& tree = grid.constTree();
    leaves.foreach ([&tree](LinkLeaf& leaf, size_t) {
        openvdb::tree::ValueAccessor<const LinkTree> acc(tree);
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            int32_t bits = it.getValue() & ~kAllLinks;
            for (int f = 0; f < kFaceCount; ++f) {
                if (acc.isValueOn(ijk + faceOffset(f))) bits |= (1 << f);
            }
            it.setValue(bits);
        }
    });
}

int64_t countLinks(const LinkGrid& grid)
{
    ConstLeafManager leaves(grid.constTree());
    std::vector<int64_t> perLeaf(leaves.leafCount(), 0);
    leaves.foreach ([&perLeaf](const LinkLeaf& leaf, size_t n) {
        int64_t count = 0;
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const int32_t bits = it.getValue();
            count += ((bits >> kPosX) & 1) + ((bits >> kPosY) & 1) + ((bits >> kPosZ) & 1);
        }
        perLeaf[n] = count;
    });
    int64_t total = 0;
    for (int64_t c : perLeaf) total += c;
    return total;
}

bool breakLink(LinkGrid::Accessor& acc, const openvdb::Coord& ijk, int face)
{
    int32_t bits = 0;
    if (!acc.probeValue(ijk, bits) || !(bits & (1 << face))) return false;
    acc.setValueOn(ijk, withBrokenFace(bits & ~(1 << face), face));
    const openvdb::Coord other = ijk + faceOffset(face);
    const int32_t otherBits = acc.getValue(other);
    acc.setValueOn(other, withBrokenFace(otherBits & ~(1 << oppositeFace(face)), oppositeFace(face)));
    return true;
}

bool linksAreSymmetric(const LinkGrid& grid)
{
    ConstLeafManager leaves(grid.constTree());
    std::vector<char> ok(leaves.leafCount(), 1);
    const LinkTree& tree = grid.constTree();
    leaves.foreach ([&](const LinkLeaf& leaf, size_t n) {
        openvdb::tree::ValueAccessor<const LinkTree> acc(tree);
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const int32_t bits = it.getValue();
            for (int f = 0; f < kFaceCount; ++f) {
                if (!(bits & (1 << f))) continue;
                int32_t other = 0;
                const bool active = acc.probeValue(it.getCoord() + faceOffset(f), other);
                if (!active || !(other & (1 << oppositeFace(f)))) ok[n] = 0;
            }
        }
    });
    for (char c : ok)
        if (!c) return false;
    return true;
}

MassProperties computeMassProperties(const LinkGrid& grid, double voxelSizeM, double densityKgM3)
{
    // Sums of first and second moments about a reference point near the body (its bounding-box
    // centre) keep the parallel-axis shift well conditioned; per-leaf partial sums are added in
    // leaf order so the result does not depend on thread count.
    struct Moments {
        int64_t n = 0;
        std::array<double, 3> s{};   // sum of d
        std::array<double, 6> ss{};  // xx yy zz xy xz yz of d
    };
    MassProperties props;
    if (grid.constTree().activeVoxelCount() == 0) return props;
    const openvdb::CoordBBox bbox = grid.evalActiveVoxelBoundingBox();
    const openvdb::Vec3d ref = (bbox.min().asVec3d() + bbox.max().asVec3d()) * 0.5;

    ConstLeafManager leaves(grid.constTree());
    std::vector<Moments> perLeaf(leaves.leafCount());
    leaves.foreach ([&](const LinkLeaf& leaf, size_t n) {
        Moments m;
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            const double x = c.x() - ref.x(), y = c.y() - ref.y(), z = c.z() - ref.z();
            ++m.n;
            m.s[0] += x; m.s[1] += y; m.s[2] += z;
            m.ss[0] += x * x; m.ss[1] += y * y; m.ss[2] += z * z;
            m.ss[3] += x * y; m.ss[4] += x * z; m.ss[5] += y * z;
        }
        perLeaf[n] = m;
    });
    Moments total;
    for (const Moments& m : perLeaf) {
        total.n += m.n;
        for (int i = 0; i < 3; ++i) total.s[i] += m.s[i];
        for (int i = 0; i < 6; ++i) total.ss[i] += m.ss[i];
    }
    const double h = voxelSizeM;
    const double n = static_cast<double>(total.n);
    const double voxelMass = densityKgM3 * h * h * h;
    props.voxelCount = total.n;
    props.massKg = voxelMass * n;
    const Eigen::Vector3d meanIndex(total.s[0] / n, total.s[1] / n, total.s[2] / n);
    props.centreOfMassLocalM = (meanIndex + Eigen::Vector3d(ref.x(), ref.y(), ref.z())) * h;

    // Second moments about the centre of mass, in index units squared.
    Eigen::Matrix3d c;
    c(0, 0) = total.ss[0] - n * meanIndex.x() * meanIndex.x();
    c(1, 1) = total.ss[1] - n * meanIndex.y() * meanIndex.y();
    c(2, 2) = total.ss[2] - n * meanIndex.z() * meanIndex.z();
    c(0, 1) = c(1, 0) = total.ss[3] - n * meanIndex.x() * meanIndex.y();
    c(0, 2) = c(2, 0) = total.ss[4] - n * meanIndex.x() * meanIndex.z();
    c(1, 2) = c(2, 1) = total.ss[5] - n * meanIndex.y() * meanIndex.z();
    // Point masses give trace(C) I - C; each cube adds its own m h^2 / 6 about every axis.
    props.inertiaKgM2 = voxelMass * h * h *
                        (c.trace() * Eigen::Matrix3d::Identity() - c + (n / 6.0) * Eigen::Matrix3d::Identity());
    return props;
}

std::vector<ExposedFace> collectExposedFaces(const LinkGrid& grid)
{
    ConstLeafManager leaves(grid.constTree());
    std::vector<std::vector<ExposedFace>> perLeaf(leaves.leafCount());
    const LinkTree& tree = grid.constTree();
    leaves.foreach ([&](const LinkLeaf& leaf, size_t n) {
        openvdb::tree::ValueAccessor<const LinkTree> acc(tree);
        auto& out = perLeaf[n];
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            for (int f = 0; f < kFaceCount; ++f) {
                if (!acc.isValueOn(ijk + faceOffset(f))) out.push_back({ijk, f});
            }
        }
    });
    std::vector<ExposedFace> all;
    size_t total = 0;
    for (const auto& v : perLeaf) total += v.size();
    all.reserve(total);
    for (const auto& v : perLeaf) all.insert(all.end(), v.begin(), v.end());
    return all;
}

std::vector<openvdb::Coord> boundaryVoxelsOf(const std::vector<ExposedFace>& faces)
{
    std::vector<openvdb::Coord> voxels;
    for (const ExposedFace& f : faces) {
        if (voxels.empty() || voxels.back() != f.voxel) voxels.push_back(f.voxel);
    }
    return voxels;
}

bool hasAnchoredVoxel(const LinkGrid& grid)
{
    for (auto it = grid.cbeginValueOn(); it; ++it)
        if (*it & kAnchorBit) return true;
    return false;
}

void refreshDerivedData(Body& body)
{
    body.mass = computeMassProperties(*body.grid, body.voxelSizeM, body.densityKgM3);
    body.exposedFaces = collectExposedFaces(*body.grid);
    body.boundaryVoxels = boundaryVoxelsOf(body.exposedFaces);
    body.indexBounds = body.grid->evalActiveVoxelBoundingBox();
    body.linkCount = countLinks(*body.grid);
    // Bounding radius over boundary voxels' far corners: every voxel lies inside it.
    double r2 = 0.0;
    const double halfDiagonal = 0.5 * std::sqrt(3.0) * body.voxelSizeM;
    for (const openvdb::Coord& v : body.boundaryVoxels) r2 = std::max(r2, body.voxelOffsetM(v).squaredNorm());
    body.boundingRadiusM = std::sqrt(r2) + halfDiagonal;
    body.anchored = hasAnchoredVoxel(*body.grid);
}

Body makeBody(LinkGrid::Ptr grid, double voxelSizeM, double densityKgM3)
{
    Body body;
    body.grid = std::move(grid);
    body.voxelSizeM = voxelSizeM;
    body.densityKgM3 = densityKgM3;
    refreshDerivedData(body);
    body.motion.positionM = body.mass.centreOfMassLocalM;
    return body;
}

void requireVoxelSize(const std::vector<Body>& bodies, double voxelSizeM)
{
    for (const Body& body : bodies) {
        if (body.voxelSizeM == voxelSizeM) continue;
        std::ostringstream message;
        message << "body " << body.id << " has voxel size " << body.voxelSizeM << " m, the scene " << voxelSizeM
                << " m: every body of a simulation has the scene's voxel size";
        throw InputError(message.str());
    }
}

}  // namespace spall
