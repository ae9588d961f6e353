#include <spall/output/FragmentSurface.h>

#include <spall/voxel/LinkBits.h>

#include <spall/core/Error.h>
#include <spall/core/Hash.h>
#include <spall/core/IntegerMath.h>
#include <spall/core/Parallel.h>

#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/LevelSetTracker.h>
#include <openvdb/tree/LeafManager.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>

namespace spall {

namespace {

/// Samples are numbered from this many before the shape's least voxel face, so a shape whose
/// voxels start at index 0 has a band of non-negative indices: one top-level node of the tree,
/// not eight (a 32^3 node each, read and written per grid).
constexpr int kSampleIndexOffset = 8;

/// The four corners of a voxel face, counter-clockwise seen from outside (unit: voxels, the voxel's
/// centre at its index).
std::array<openvdb::Vec3s, 4> faceCorners(const VoxelFace& f)
{
    const int axis = faceAxis(f.face), u = (axis + 1) % 3, v = (axis + 2) % 3;
    const float sign = float(faceSign(f.face));
    openvdb::Vec3s centre(float(f.voxel.x()), float(f.voxel.y()), float(f.voxel.z()));
    centre[axis] += 0.5f * sign;
    std::array<openvdb::Vec3s, 4> corners;
    const float du[4] = {-0.5f, 0.5f, 0.5f, -0.5f}, dv[4] = {-0.5f, -0.5f, 0.5f, 0.5f};
    for (int i = 0; i < 4; ++i) {
        corners[i] = centre;
        corners[i][u] += du[i];
        corners[i][v] += sign * dv[i];  // flip the winding on the negative side: outward either way
    }
    return corners;
}

/// The volume inside closed voxel faces (unit: voxels), by the divergence theorem: each face adds
/// a third of (its centre · its outward normal) times its area of 1.
double enclosedVolume(const std::vector<VoxelFace>& faces)
{
    double sum = 0.0;
    // centre · normal = (voxel[axis] + sign / 2) * sign.
    for (const VoxelFace& f : faces) sum += faceSign(f.face) * f.voxel[faceAxis(f.face)] + 0.5;
    return sum / 3.0;
}

/// Smooth value noise in [-1, 1] of a position in lattice units: random values at the integer
/// points blended with smoothstep weights (value noise, Perlin 1985). A function of position
/// alone, so equal shapes get equal surfaces and faces that meet agree where they meet.
double valueNoise(const openvdb::Vec3d& x)
{
    const openvdb::Coord cell = openvdb::Coord::floor(x);
    const openvdb::Vec3d f = x - cell.asVec3d();
    const openvdb::Vec3d w(f.x() * f.x() * (3 - 2 * f.x()), f.y() * f.y() * (3 - 2 * f.y()), f.z() * f.z() * (3 - 2 * f.z()));
    double sum = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const openvdb::Coord c = cell.offsetBy(corner & 1, (corner >> 1) & 1, corner >> 2);
        double weight = 1.0;
        for (int axis = 0; axis < 3; ++axis) weight *= (corner >> axis & 1) ? w[axis] : 1.0 - w[axis];
        const uint64_t key = uint64_t(uint32_t(c.x())) ^ uint64_t(uint32_t(c.y())) << 21 ^ uint64_t(uint32_t(c.z())) << 42;
        sum += weight * (2.0 * unitInterval(splitmix64(key)) - 1.0);
    }
    return sum;
}

/// The quads of voxel faces (unit: m in the shape's frame) that `keep` selects.
void faceQuads(const std::vector<VoxelFace>& faces, double voxelSizeM, const std::function<bool(const VoxelFace&)>& keep,
               std::vector<openvdb::Vec3s>& points, std::vector<openvdb::Vec4I>& quads)
{
    for (const VoxelFace& f : faces) {
        if (!keep(f)) continue;
        const auto base = static_cast<openvdb::Index32>(points.size());
        for (const openvdb::Vec3s& c : faceCorners(f)) points.push_back(c * float(voxelSizeM));
        quads.emplace_back(base, base + 1, base + 2, base + 3);
    }
}

/// Lattice spacing of the fracture noise (unit: voxel edges): bumps about a voxel across, which
/// the default 3 samples per voxel resolve roughly and 4 or more well.
constexpr double kNoiseLatticeVoxels = 0.5;
/// Within this distance of the object's own surface the noise fades out (unit: voxel edges).
constexpr double kNoiseFadeVoxels = 0.5;

/// The unsigned distance to those of the object's own faces (not fracture surface) that `near`
/// selects on the level set's samples, out to a sample beyond kNoiseFadeVoxels (unit: m); null when
/// it has none.
openvdb::FloatGrid::Ptr distanceToOwnFaces(const openvdb::FloatGrid& levelSet, const std::vector<VoxelFace>& faces, double voxelSizeM,
                                           int subdivisions, const std::function<bool(const VoxelFace&)>& near = {})
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec4I> quads;
    faceQuads(faces, voxelSizeM, [&](const VoxelFace& f) { return !f.fracture && (!near || near(f)); }, points, quads);
    if (quads.empty()) return nullptr;
    const std::vector<openvdb::Vec3I> noTriangles;
    return openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(levelSet.transform(), points, noTriangles, quads,
                                                                           float(kNoiseFadeVoxels * subdivisions) + 1.0f);
}

using FloatLeaf = openvdb::FloatTree::LeafNodeType;

/// A leaf of the level set's tree as one voxel of a mask: its origin over the leaf's edge.
openvdb::Coord leafCell(const openvdb::Coord& sample) { return openvdb::Coord(sample.x() >> FloatLeaf::LOG2DIM, sample.y() >> FloatLeaf::LOG2DIM, sample.z() >> FloatLeaf::LOG2DIM); }
openvdb::Coord leafOrigin(const openvdb::Coord& cell)
{
    constexpr int dim = int(FloatLeaf::DIM);  // a multiplication: shifting a negative cell left is undefined
    return openvdb::Coord(cell.x() * dim, cell.y() * dim, cell.z() * dim);
}

/// The leaves (as leafCell) holding samples of `face`.
openvdb::CoordBBox leafCellsOf(const openvdb::FloatGrid& levelSet, const VoxelFace& face, double voxelSizeM)
{
    openvdb::CoordBBox cells;
    for (const openvdb::Vec3s& corner : faceCorners(face)) {
        const openvdb::Coord sample = openvdb::Coord::round(levelSet.transform().worldToIndex(openvdb::Vec3d(corner) * voxelSizeM));
        cells.expand(leafCell(sample));
    }
    return cells;
}

/// The level set's leaves within `dilation` leaves of a fracture face, as leafCell.
openvdb::MaskTree leavesNearFractureFaces(const openvdb::FloatGrid& levelSet, const std::vector<VoxelFace>& faces, double voxelSizeM, int dilation)
{
    openvdb::MaskTree near(false);
    openvdb::tree::ValueAccessor<openvdb::MaskTree> mark(near);
    for (const VoxelFace& f : faces) {
        if (!f.fracture) continue;
        const openvdb::CoordBBox cells = leafCellsOf(levelSet, f, voxelSizeM);
        for (auto c = cells.begin(); c; ++c) mark.setValueOn(*c);
    }
    if (dilation > 0) openvdb::tools::dilateActiveValues(near, dilation, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    return near;
}

/// Copies the leaves (or the tiles, at a leaf's size) of `from` that `cells` holds into `to`,
/// replacing what `to` had there.
void copyLeaves(const openvdb::FloatGrid& from, openvdb::FloatGrid& to, const openvdb::MaskTree& cells)
{
    for (auto cell = cells.cbeginValueOn(); cell; ++cell) {
        const openvdb::Coord origin = leafOrigin(cell.getCoord());
        if (const FloatLeaf* leaf = from.tree().probeConstLeaf(origin))
            to.tree().addLeaf(new FloatLeaf(*leaf));
        else
            to.tree().addTile(1, origin, from.tree().getValue(origin), false);
    }
}

/// A level set of the leaves (and tiles) of `levelSet` that `cells` holds.
openvdb::FloatGrid::Ptr copyOfLeaves(const openvdb::FloatGrid& levelSet, const openvdb::MaskTree& cells)
{
    openvdb::FloatGrid::Ptr region = openvdb::FloatGrid::create(levelSet.background());
    region->setTransform(levelSet.transform().copy());
    region->setGridClass(openvdb::GRID_LEVEL_SET);
    copyLeaves(levelSet, *region, cells);
    return region;
}

/// The volume the mesh readers make of the level set encloses, counted in the leaves `cells`
/// holds: its triangles' (centroid in those leaves) signed volumes about `aboutM`, times
/// `winding` (the sign of a closed mesh's signedVolumeM3 from this mesher). Of two level sets
/// that differ only well inside those leaves, the difference is the difference of their volumes
/// (unit: m³).
double volumeInLeaves(const openvdb::FloatGrid& levelSet, const openvdb::MaskTree& cells, const Eigen::Vector3d& aboutM, double winding)
{
    const SurfaceMesh mesh = meshLevelSet(levelSet);
    double sixVolumes = 0.0;
    for (const auto& t : mesh.triangles) {
        const Eigen::Vector3d a = mesh.pointsM[t[0]] - aboutM, b = mesh.pointsM[t[1]] - aboutM, c = mesh.pointsM[t[2]] - aboutM;
        const Eigen::Vector3d centroid = aboutM + (a + b + c) / 3.0;
        const openvdb::Coord sample = openvdb::Coord::round(levelSet.transform().worldToIndex(openvdb::Vec3d(centroid.x(), centroid.y(), centroid.z())));
        if (cells.isValueOn(leafCell(sample))) sixVolumes += a.dot(b.cross(c));
    }
    return winding * sixVolumes / 6.0;
}

/// The centre of the leaves `cells` holds, in the world (unit: m).
Eigen::Vector3d centreOfLeaves(const openvdb::FloatGrid& levelSet, const openvdb::MaskTree& cells)
{
    openvdb::CoordBBox box;
    cells.evalActiveVoxelBoundingBox(box);
    const openvdb::Vec3d centre = levelSet.indexToWorld((leafOrigin(box.min()).asVec3d() + leafOrigin(box.max() + openvdb::Coord(1)).asVec3d()) * 0.5);
    return Eigen::Vector3d(centre.x(), centre.y(), centre.z());
}

/// The flow and the volume's correction change samples within a leaf (8 samples) of a fracture
/// face at the default 4 steps, to float rounding: the leaves written back. A flow of more steps
/// reaches further (the surface moves about steps / 3 samples over a crack's radius in samples),
/// so the region grows by a leaf every kStepsPerLeaf steps.
constexpr int kChangedLeaves = 1;
/// Around those, leaves that the flow works on but that are not written back: the flow's
/// renormalisation reads samples a few leaves off, and where the copy ends it reads the
/// background, an error that spreads about a sample a step.
constexpr int kHaloLeaves = 2;
constexpr int kStepsPerLeaf = 8;

/// Mean-curvature flow of the fracture surface alone: the flow's step is blended out toward the
/// object's own faces (OpenVDB's alpha mask: a smoothstep of the distance to them, 0 on them, 1
/// half a voxel away), so a box stays a box and its cracks lose their staircase; then the solid
/// is grown back to its voxels' volume by moving the fracture surface alone, by the missing
/// volume over the fracture faces' area, measured on the mesh readers make (three times, as the
/// area changes with it). No own faces: the whole surface flows. Only the leaves near fracture
/// faces change, so the flow works on a copy of those and a halo around them, and writes back
/// the first: a wall's frame pays for its cracks, not for its faces.
void smoothFractureFaces(openvdb::FloatGrid& levelSet, const std::vector<VoxelFace>& faces, double voxelSizeM, const SurfaceStyle& style)
{
    const int grownLeaves = style.smoothingSteps / kStepsPerLeaf;
    const openvdb::MaskTree changed = leavesNearFractureFaces(levelSet, faces, voxelSizeM, kChangedLeaves + grownLeaves);
    const openvdb::MaskTree worked = leavesNearFractureFaces(levelSet, faces, voxelSizeM, kChangedLeaves + kHaloLeaves + 2 * grownLeaves);
    const openvdb::FloatGrid::Ptr region = copyOfLeaves(levelSet, worked);
    const auto inRegion = [&](const VoxelFace& f) {
        const openvdb::CoordBBox cells = leafCellsOf(levelSet, f, voxelSizeM);
        return worked.isValueOn(cells.min()) || worked.isValueOn(cells.max());
    };
    const openvdb::FloatGrid::Ptr own = distanceToOwnFaces(*region, faces, voxelSizeM, style.subdivisions, inRegion);
    // The whole's volume as it will be: as it was but for what changes in the changed leaves.
    const double wholeSignedM3 = meshLevelSet(levelSet).signedVolumeM3(), winding = wholeSignedM3 < 0.0 ? -1.0 : 1.0;
    const Eigen::Vector3d aboutM = centreOfLeaves(levelSet, changed);
    const double changedBeforeM3 = volumeInLeaves(*region, changed, aboutM, winding);
    openvdb::tools::LevelSetFilter<openvdb::FloatGrid, openvdb::FloatGrid> filter(*region);
    // One pass of the tracker's renormalisation after each step, first-order upwind, not
    // OpenVDB's three of fifth-order HJ-WENO: a few short steps from an exact distance leave
    // little to correct (the staircase's area and the volume come out the same to 2e-4), and the
    // WENO passes were most of the smoothing's time.
    filter.setNormCount(1);
    filter.setSpatialScheme(openvdb::math::FIRST_BIAS);
    if (own) filter.setMaskRange(0.0f, float(kNoiseFadeVoxels * voxelSizeM));
    for (int i = 0; i < style.smoothingSteps; ++i) filter.meanCurvature(own.get());
    const double fractureAreaM2 = double(std::count_if(faces.begin(), faces.end(), [](const VoxelFace& f) { return f.fracture; })) * voxelSizeM * voxelSizeM;
    const double voxelVolumeM3 = enclosedVolume(faces) * std::pow(voxelSizeM, 3);
    for (int i = 0; i < 3; ++i) {
        const double volumeM3 = std::abs(wholeSignedM3) + volumeInLeaves(*region, changed, aboutM, winding) - changedBeforeM3;
        filter.offset(float(-(voxelVolumeM3 - volumeM3) / fractureAreaM2), own.get());  // a negative offset grows the solid
    }
    copyLeaves(*region, levelSet, changed);
}

/// Moves the zero surface outward by roughness * voxelSizeM * noise * fade, where fade rises from
/// 0 on the object's own faces to 1 half a voxel away (smoothstep of the distance to them), then
/// restores the distance property. No own faces: the noise applies everywhere.
void roughenFractureFaces(openvdb::FloatGrid& levelSet, const std::vector<VoxelFace>& faces, double voxelSizeM, double roughness,
                          int subdivisions)
{
    const openvdb::FloatGrid::Ptr ownDistance = distanceToOwnFaces(levelSet, faces, voxelSizeM, subdivisions);
    const double amplitudeM = roughness * voxelSizeM;
    const double fadeM = kNoiseFadeVoxels * voxelSizeM;
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(levelSet.tree());
    leaves.foreach([&](openvdb::FloatTree::LeafNodeType& leaf, size_t) {
        auto own = ownDistance ? std::optional(ownDistance->getConstAccessor()) : std::nullopt;
        for (auto it = leaf.beginValueOn(); it; ++it) {
            double fade = 1.0;
            if (own) {
                const double t = std::min(1.0, double(own->getValue(it.getCoord())) / fadeM);
                fade = t * t * (3 - 2 * t);
            }
            if (fade == 0.0) continue;
            // The sample's place in voxel units, then in noise-lattice units.
            const openvdb::Vec3d voxel = (it.getCoord().asVec3d() - openvdb::Vec3d(kSampleIndexOffset)) / double(subdivisions);
            it.setValue(float(*it - amplitudeM * fade * valueNoise(voxel / kNoiseLatticeVoxels)));
        }
    });
    openvdb::tools::LevelSetTracker<openvdb::FloatGrid> tracker(levelSet);
    tracker.normalize();
}

}  // namespace

SurfaceMesh meshLevelSet(const openvdb::FloatGrid& levelSet, double adaptivity)
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(levelSet, points, triangles, quads, 0.0, adaptivity);
    SurfaceMesh mesh;
    mesh.pointsM.reserve(points.size());
    for (const openvdb::Vec3s& p : points) mesh.pointsM.emplace_back(p.x(), p.y(), p.z());
    mesh.triangles.reserve(triangles.size() + 2 * quads.size());
    for (const auto& t : triangles) mesh.triangles.push_back({t[0], t[1], t[2]});
    for (const auto& q : quads) {
        mesh.triangles.push_back({q[0], q[1], q[2]});
        mesh.triangles.push_back({q[0], q[2], q[3]});
    }
    return mesh;
}

double SurfaceMesh::signedVolumeM3() const
{
    if (pointsM.empty()) return 0.0;
    const Eigen::Vector3d& o = pointsM.front();  // about a point of the mesh: no precision lost far from the origin
    double sixVolumes = 0.0;
    for (const auto& t : triangles) sixVolumes += (pointsM[t[0]] - o).dot((pointsM[t[1]] - o).cross(pointsM[t[2]] - o));
    return sixVolumes / 6.0;
}

double SurfaceMesh::areaM2() const
{
    double twiceArea = 0.0;
    for (const auto& t : triangles) twiceArea += (pointsM[t[1]] - pointsM[t[0]]).cross(pointsM[t[2]] - pointsM[t[0]]).norm();
    return 0.5 * twiceArea;
}

openvdb::math::Transform::Ptr levelSetTransform(const openvdb::math::Transform& voxelIndexToWorld, int subdivisions)
{
    // world = voxelIndexToWorld((u - offset) / k - 0.5): pre-operations act in reverse order.
    auto transform = voxelIndexToWorld.copy();
    transform->preTranslate(openvdb::Vec3d(-0.5));
    transform->preScale(1.0 / subdivisions);
    transform->preTranslate(openvdb::Vec3d(-kSampleIndexOffset));
    return transform;
}

openvdb::math::Transform::Ptr voxelTransformOf(const openvdb::math::Transform& levelSetTransform, int subdivisions)
{
    // Voxel c's centre is sample k (c + 0.5) + offset: pre-operations act in reverse order.
    auto voxelMap = levelSetTransform.copy();
    voxelMap->preTranslate(openvdb::Vec3d(0.5 * subdivisions + kSampleIndexOffset));
    voxelMap->preScale(double(subdivisions));
    return voxelMap;
}

namespace {

/// The samples within `band` samples of face `f` (a box of sample indices, both ends in).
openvdb::CoordBBox samplesNearFace(const VoxelFace& f, int k, int band)
{
    openvdb::Coord lo, hi;
    for (int axis = 0; axis < 3; ++axis) {
        // Voxel v's cube spans samples k v + offset to k (v + 1) + offset (levelSetTransform).
        const int low = k * f.voxel[axis] + kSampleIndexOffset;
        const int plane = faceSign(f.face) > 0 ? low + k : low;
        lo[axis] = (axis == faceAxis(f.face) ? plane : low) - band;
        hi[axis] = (axis == faceAxis(f.face) ? plane : low + k) + band;
    }
    return {lo, hi};
}

/// Squared distance from sample `u` to a face's square, given as its samples (samplesNearFace
/// with no band) (unit: samples², exact in integers).
int squaredSampleDistance(const openvdb::Coord& u, const openvdb::CoordBBox& square)
{
    int sum = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const int gap = u[axis] < square.min()[axis] ? square.min()[axis] - u[axis] : std::max(0, u[axis] - square.max()[axis]);
        sum += gap * gap;
    }
    return sum;
}

/// Every distance less this (unit: m), as OpenVDB's meshToLevelSet leaves them: a sample on a face
/// lies a hair inside, so volume-to-mesh (inside below 0) puts the surface on the face.
constexpr float kOnFaceInsideM = 1e-7f;

/// The level-set leaf at leafOrigin(cell) of a union of voxel cubes: the exact distance from each
/// sample to the nearest of the `nearby` faces (the union's boundary is its exposed faces), active
/// within the band, signed by whether the voxel holding the sample is solid (a sample between a
/// solid and an empty voxel lies on an exposed face). Null when no sample is in the band.
FloatLeaf* distanceLeaf(const openvdb::Coord& cell, const std::vector<const VoxelFace*>& nearby, const openvdb::FloatTree& voxels, int k,
                        float halfWidthSamples, float sampleM)
{
    const openvdb::Coord origin = leafOrigin(cell);
    std::array<int, FloatLeaf::SIZE> nearest;
    nearest.fill(std::numeric_limits<int>::max());
    const openvdb::CoordBBox leafBox(origin, origin.offsetBy(int(FloatLeaf::DIM) - 1));
    const int band = int(std::ceil(halfWidthSamples));
    for (const VoxelFace* f : nearby) {
        openvdb::CoordBBox box = samplesNearFace(*f, k, band);
        box.intersect(leafBox);
        if (box.empty()) continue;
        const openvdb::CoordBBox square = samplesNearFace(*f, k, 0);
        for (auto u = box.begin(); u; ++u) {
            int& d2 = nearest[FloatLeaf::coordToOffset(*u)];
            d2 = std::min(d2, squaredSampleDistance(*u, square));
        }
    }
    const float background = halfWidthSamples * sampleM;
    auto leaf = std::make_unique<FloatLeaf>(origin, background);
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> solid(voxels);
    bool any = false;
    for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i) {
        const openvdb::Coord u = FloatLeaf::offsetToLocalCoord(i) + origin;
        const openvdb::Coord voxel(floorDivide(u.x() - kSampleIndexOffset, k), floorDivide(u.y() - kSampleIndexOffset, k),
                                   floorDivide(u.z() - kSampleIndexOffset, k));
        const float sign = solid.isValueOn(voxel) ? -1.0f : 1.0f;
        const float d = nearest[i] == std::numeric_limits<int>::max() ? halfWidthSamples : std::sqrt(float(nearest[i]));
        if (d < halfWidthSamples) {
            leaf->setValueOn(i, sign * d * sampleM - kOnFaceInsideM);
            any = true;
        } else {
            leaf->setValueOff(i, sign * background);
        }
    }
    return any ? leaf.release() : nullptr;
}

/// The narrow-band signed distance (unit: m) to the union of the voxel cubes `voxels` whose
/// boundary is `faces`, on samples `subdivisions` per voxel edge (levelSetTransform). Exact: each
/// sample takes the least distance to the faces whose band reaches it, in integers of samples
/// (OpenVDB's meshToLevelSet does this for any polygons, and renormalises after).
openvdb::FloatGrid::Ptr voxelUnionDistance(const std::vector<VoxelFace>& faces, const openvdb::FloatTree& voxels, double voxelSizeM,
                                           const SurfaceStyle& style)
{
    const int k = style.subdivisions, band = int(std::ceil(style.halfWidthSamples));
    SPALL_CHECK(band <= kSampleIndexOffset);  // the band fits the index offset: leaves stay at non-negative cells
    // Each face under every leaf its band reaches, grouped by leaf.
    std::vector<std::pair<uint64_t, uint32_t>> cellFaces;
    cellFaces.reserve(8 * faces.size());
    constexpr int kKeyBits = 21;
    const auto key = [](const openvdb::Coord& c) { return uint64_t(c.x()) | uint64_t(c.y()) << kKeyBits | uint64_t(c.z()) << (2 * kKeyBits); };
    for (size_t i = 0; i < faces.size(); ++i) {
        const openvdb::CoordBBox box = samplesNearFace(faces[i], k, band);
        for (auto c = openvdb::CoordBBox(leafCell(box.min()), leafCell(box.max())).begin(); c; ++c) cellFaces.emplace_back(key(*c), uint32_t(i));
    }
    std::sort(cellFaces.begin(), cellFaces.end());
    std::vector<size_t> groupStart;
    for (size_t i = 0; i < cellFaces.size(); ++i)
        if (i == 0 || cellFaces[i].first != cellFaces[i - 1].first) groupStart.push_back(i);
    groupStart.push_back(cellFaces.size());
    const float sampleM = float(voxelSizeM / k);
    std::vector<FloatLeaf*> leaves(groupStart.size() - 1, nullptr);
    forEachIndex(leaves.size(), [&](size_t g) {
        std::vector<const VoxelFace*> nearby;
        for (size_t i = groupStart[g]; i < groupStart[g + 1]; ++i) nearby.push_back(&faces[cellFaces[i].second]);
        const uint64_t cellKey = cellFaces[groupStart[g]].first, mask = (uint64_t(1) << kKeyBits) - 1;
        const openvdb::Coord cell(int(cellKey & mask), int(cellKey >> kKeyBits & mask), int(cellKey >> (2 * kKeyBits)));
        leaves[g] = distanceLeaf(cell, nearby, voxels, k, style.halfWidthSamples, sampleM);
    });
    auto levelSet = openvdb::FloatGrid::create(style.halfWidthSamples * sampleM);
    levelSet->setTransform(levelSetTransform(*openvdb::math::Transform::createLinearTransform(voxelSizeM), k));
    levelSet->setGridClass(openvdb::GRID_LEVEL_SET);
    for (FloatLeaf* leaf : leaves)
        if (leaf) levelSet->tree().addLeaf(leaf);
    openvdb::tools::signedFloodFill(levelSet->tree());
    return levelSet;
}

}  // namespace

openvdb::FloatTree::Ptr voxelSurfaceLevelSet(const std::vector<VoxelFace>& faces, const openvdb::FloatTree& voxels, double voxelSizeM,
                                             const SurfaceStyle& style)
{
    const openvdb::FloatGrid::Ptr levelSet = voxelUnionDistance(faces, voxels, voxelSizeM, style);
    const bool broken = std::any_of(faces.begin(), faces.end(), [](const VoxelFace& f) { return f.fracture; });
    if (style.smoothingSteps > 0 && broken) smoothFractureFaces(*levelSet, faces, voxelSizeM, style);
    if (style.fractureRoughness > 0.0 && broken)
        roughenFractureFaces(*levelSet, faces, voxelSizeM, style.fractureRoughness, style.subdivisions);
    return levelSet->treePtr();
}

namespace {

/// The level-set leaf (as leafCell) holding sample `sample` along one axis.
int cellOf(int sample) { return sample >> FloatLeaf::LOG2DIM; }

/// Voxel v's cube spans samples k v + kSampleIndexOffset to k (v + 1) + kSampleIndexOffset
/// (levelSetTransform): the leaves holding those, `reach` samples either side, marked in `cells`.
void markLeavesNear(const openvdb::Coord& voxel, int k, int reach, openvdb::tree::ValueAccessor<openvdb::MaskTree>& cells)
{
    openvdb::Coord lo, hi;
    for (int axis = 0; axis < 3; ++axis) {
        lo[axis] = cellOf(k * voxel[axis] + kSampleIndexOffset - reach);
        hi[axis] = cellOf(k * (voxel[axis] + 1) + kSampleIndexOffset + reach);
    }
    for (int x = lo.x(); x <= hi.x(); ++x)
        for (int y = lo.y(); y <= hi.y(); ++y)
            for (int z = lo.z(); z <= hi.z(); ++z) cells.setValueOn(openvdb::Coord(x, y, z));
}

/// Whether two leaves (either may be null: none) hold the same voxels with the same values.
bool sameLeaf(const FloatLeaf* a, const FloatLeaf* b)
{
    if (!a || !b) return a == b;
    if (a->getValueMask() != b->getValueMask()) return false;
    for (auto it = a->cbeginValueOn(); it; ++it)
        if (b->getValue(it.pos()) != *it) return false;
    return true;
}

/// The voxels where two shapes differ (one holds it, the other not, or its broken faces
/// differ), among the blocks of voxels (leaves of the voxel trees) next to those of `after`:
/// farther ones cannot reach its level set.
std::vector<openvdb::Coord> voxelsThatDiffer(const VoxelShape& before, const VoxelShape& after)
{
    openvdb::MaskTree blocks(false);
    for (auto leaf = after.voxels->cbeginLeaf(); leaf; ++leaf) blocks.setValueOn(leafCell(leaf->origin()));
    openvdb::tools::dilateActiveValues(blocks, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    std::vector<openvdb::Coord> differ;
    const auto compare = [&](const VoxelShape& first, const VoxelShape& second, bool seenBoth) {
        for (auto leaf = first.voxels->cbeginLeaf(); leaf; ++leaf) {
            const openvdb::Coord origin = leaf->origin();
            if (!blocks.isValueOn(leafCell(origin))) continue;
            const FloatLeaf* other = second.voxels->probeConstLeaf(origin);
            if (other && !seenBoth) continue;
            const FloatLeaf *brokenFirst = first.brokenFaceBits->probeConstLeaf(origin), *brokenSecond = second.brokenFaceBits->probeConstLeaf(origin);
            if (other && other->getValueMask() == leaf->getValueMask() && sameLeaf(brokenFirst, brokenSecond)) continue;
            for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i) {
                const bool inFirst = leaf->isValueOn(i), inSecond = other && other->isValueOn(i);
                const float bitsFirst = brokenFirst ? brokenFirst->getValue(i) : 0.0f, bitsSecond = brokenSecond ? brokenSecond->getValue(i) : 0.0f;
                if ((inFirst || inSecond) && (inFirst != inSecond || bitsFirst != bitsSecond)) differ.push_back(leaf->offsetToGlobalCoord(i));
            }
        }
    };
    compare(before, after, true);
    compare(after, before, false);
    return differ;
}

/// The faces of `shape`'s voxels whose centres' samples lie in the `worked` leaves: their exposed
/// faces (broken or not, as `shape` says), and where they meet voxels outside, cut faces taken as
/// the object's own (they close the region's solid and neither flow nor roughen).
std::vector<VoxelFace> facesOfRegion(const VoxelShape& shape, const openvdb::MaskTree& worked, int k, openvdb::FloatTree& regionVoxels)
{
    openvdb::tree::ValueAccessor<const openvdb::MaskTree> inWorked(worked);
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> solid(*shape.voxels), broken(*shape.brokenFaceBits);
    const auto centreCell = [&](int v) { return cellOf(k * v + kSampleIndexOffset + k / 2); };
    const auto inRegion = [&](const openvdb::Coord& v) { return inWorked.isValueOn(openvdb::Coord(centreCell(v.x()), centreCell(v.y()), centreCell(v.z()))); };
    // The voxels whose centre's sample k v + offset + k/2 lies in leaf c: from ceil to floor.
    const int leafEdge = int(FloatLeaf::DIM);
    const auto firstVoxel = [&](int c) { return floorDivide(leafEdge * c - kSampleIndexOffset - k / 2 + k - 1, k); };
    const auto lastVoxel = [&](int c) { return floorDivide(leafEdge * c + leafEdge - 1 - kSampleIndexOffset - k / 2, k); };
    std::vector<VoxelFace> faces;
    openvdb::tree::ValueAccessor<openvdb::FloatTree> inRegionVoxels(regionVoxels);
    for (auto cell = worked.cbeginValueOn(); cell; ++cell) {
        const openvdb::Coord c = cell.getCoord();
        for (int x = firstVoxel(c.x()); x <= lastVoxel(c.x()); ++x)
            for (int y = firstVoxel(c.y()); y <= lastVoxel(c.y()); ++y)
                for (int z = firstVoxel(c.z()); z <= lastVoxel(c.z()); ++z) {
                    const openvdb::Coord v(x, y, z);
                    if (!solid.isValueOn(v)) continue;
                    inRegionVoxels.setValueOn(v, 1.0f);
                    const int bits = int(broken.getValue(v));
                    for (int f = 0; f < kFaceCount; ++f) {
                        const openvdb::Coord across = v + faceOffset(f);
                        if (!solid.isValueOn(across))
                            faces.push_back({v, f, (bits & (1 << f)) != 0});
                        else if (!inRegion(across))
                            faces.push_back({v, f, false});
                    }
                }
    }
    return faces;
}

/// The level-set leaves a shape's level set can have samples in: those of its voxels' blocks
/// and a leaf around them (the band reaches at most a leaf out).
openvdb::MaskTree leavesOfShape(const openvdb::FloatTree& voxels, int k)
{
    openvdb::MaskTree cells(false);
    openvdb::tree::ValueAccessor<openvdb::MaskTree> mark(cells);
    for (auto leaf = voxels.cbeginLeaf(); leaf; ++leaf) {
        const openvdb::Coord first = leaf->origin();
        // A block's samples start at leaf k * (block) + 1 and span k leaves (kSampleIndexOffset is one leaf).
        const openvdb::Coord cell(cellOf(k * first.x() + kSampleIndexOffset), cellOf(k * first.y() + kSampleIndexOffset),
                                  cellOf(k * first.z() + kSampleIndexOffset));
        for (int x = -1; x <= k; ++x)
            for (int y = -1; y <= k; ++y)
                for (int z = -1; z <= k; ++z) mark.setValueOn(cell.offsetBy(x, y, z));
    }
    return cells;
}

/// How far a change of the voxels reaches in a level set (unit: samples), and how many leaves
/// around those an update works on to remake them: a level set's samples depend on the voxels
/// within its band, a smoothed or roughened one's on those a few leaves further.
struct UpdateReach {
    int rewrittenSamples = 3;
    int haloLeaves = 1;
};

UpdateReach updateReachOf(const SurfaceStyle& style)
{
    const int band = int(std::ceil(style.halfWidthSamples)), leaf = int(FloatLeaf::DIM);
    const int grownLeaves = style.smoothingSteps / kStepsPerLeaf;
    const int roughening = style.fractureRoughness > 0.0 ? leaf : 0;  // the renormalisation's stencil
    const int smoothed = style.smoothingSteps > 0 ? leaf * (kChangedLeaves + grownLeaves) : 0;
    const int smoothingHalo = style.smoothingSteps > 0 ? leaf * (kHaloLeaves + 2 * grownLeaves) : 0;
    UpdateReach reach;
    // A sample depends on the faces within its band; two samples more as a margin.
    reach.rewrittenSamples = band + 2 + smoothed + roughening;
    // A region's voxel reaches its leaf from up to a voxel away: the halo adds k samples.
    reach.haloLeaves = (band + smoothingHalo + roughening + style.subdivisions + leaf - 1) / leaf;
    return reach;
}

/// The leaves (or the tiles at a leaf's size) of `from` at `cells`, added to `to`.
void copyCells(const openvdb::FloatTree& from, openvdb::FloatTree& to, const openvdb::MaskTree& cells)
{
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> read(from);
    for (auto cell = cells.cbeginValueOn(); cell; ++cell) {
        const openvdb::Coord origin = leafOrigin(cell.getCoord());
        if (const FloatLeaf* leaf = read.probeConstLeaf(origin))
            to.addLeaf(new FloatLeaf(*leaf));
        else
            to.addTile(1, origin, read.getValue(origin), false);
    }
}

}  // namespace

openvdb::FloatTree::Ptr updatedVoxelSurfaceLevelSet(const VoxelShapeSurface& previous, const VoxelShape& now, size_t exposedFaceCount,
                                                    double voxelSizeM, const SurfaceStyle& style)
{
    const int k = style.subdivisions;
    const UpdateReach reach = updateReachOf(style);
    const openvdb::MaskTree shapeLeaves = leavesOfShape(*now.voxels, k);
    openvdb::MaskTree rewritten(false);
    {
        openvdb::tree::ValueAccessor<openvdb::MaskTree> mark(rewritten);
        for (const openvdb::Coord& v : voxelsThatDiffer(previous.shape, now)) markLeavesNear(v, k, reach.rewrittenSamples, mark);
    }
    rewritten.topologyIntersection(shapeLeaves);
    openvdb::MaskTree worked(rewritten);
    openvdb::tools::dilateActiveValues(worked, reach.haloLeaves, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    openvdb::FloatTree regionVoxels(0.0f);
    const std::vector<VoxelFace> region = facesOfRegion(now, worked, k, regionVoxels);
    // The region costs about what it would in a whole surface: past half the shape's faces, the
    // whole is as cheap (and exact).
    if (2 * region.size() > exposedFaceCount) return nullptr;
    openvdb::MaskTree kept(shapeLeaves);
    kept.topologyDifference(rewritten);
    auto updated = std::make_shared<openvdb::FloatTree>(previous.surface->background());
    copyCells(*previous.surface, *updated, kept);
    if (!rewritten.empty())
        copyCells(region.empty() ? openvdb::FloatTree(previous.surface->background()) : *voxelSurfaceLevelSet(region, regionVoxels, voxelSizeM, style), *updated,
                  rewritten);
    return updated;
}

openvdb::FloatGrid::Ptr voxelsOfLevelSet(const openvdb::FloatGrid& levelSet, int subdivisions)
{
    const int k = subdivisions;
    auto voxels = openvdb::FloatGrid::create(0.0f);
    voxels->setTransform(voxelTransformOf(levelSet.transform(), subdivisions));
    voxels->setGridClass(openvdb::GRID_FOG_VOLUME);
    // Unsmoothed, a centre inside lies at least half a voxel within the surface (k even), or at a
    // third of one (k odd, where it is no sample: the mean of samples a third of a voxel in); one
    // outside, at least half a voxel out. Rough (at most 0.2 of a voxel) or smoothed fracture
    // faces move less than that, so the sign at the centre still tells.
    const float threshold = 0.0f;
    // The sampler keeps a pointer to the accessor: it must outlive the sampler.
    const openvdb::FloatGrid::ConstAccessor levelSetAccess = levelSet.getConstAccessor();
    openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(levelSetAccess, levelSet.transform());
    auto out = voxels->getAccessor();
    for (auto it = levelSet.cbeginValueOn(); it; ++it) {
        if (*it > 0.0f) continue;
        const openvdb::Vec3d c = (it.getCoord().asVec3d() - openvdb::Vec3d(kSampleIndexOffset)) / double(k) - openvdb::Vec3d(0.5);
        const openvdb::Coord voxel = openvdb::Coord::round(c);
        if (out.isValueOn(voxel)) continue;
        const openvdb::Vec3d centre = openvdb::Vec3d(k * (voxel.x() + 0.5), k * (voxel.y() + 0.5), k * (voxel.z() + 0.5)) +
                                      openvdb::Vec3d(kSampleIndexOffset);
        if (sampler.isSample(centre) < threshold)
            out.setValueOn(voxel, 1.0f);
    }
    return voxels;
}

}  // namespace spall
