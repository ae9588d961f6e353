#include <spall/output/FragmentSurface.h>

#include <spall/voxel/LinkBits.h>

#include <spall/core/Error.h>
#include <spall/core/Hash.h>

#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/LevelSetTracker.h>
#include <openvdb/tree/LeafManager.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
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

openvdb::FloatTree::Ptr voxelSurfaceLevelSet(const std::vector<VoxelFace>& faces, double voxelSizeM, const SurfaceStyle& style)
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec4I> quads;
    points.reserve(4 * faces.size());
    quads.reserve(faces.size());
    faceQuads(faces, voxelSizeM, [](const VoxelFace&) { return true; }, points, quads);
    const auto shapeSpace = levelSetTransform(*openvdb::math::Transform::createLinearTransform(voxelSizeM), style.subdivisions);
    const std::vector<openvdb::Vec3I> noTriangles;
    SPALL_CHECK(style.halfWidthSamples <= kSampleIndexOffset);  // the band fits the index offset
    auto levelSet = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*shapeSpace, points, noTriangles, quads, style.halfWidthSamples);
    const bool broken = std::any_of(faces.begin(), faces.end(), [](const VoxelFace& f) { return f.fracture; });
    if (style.smoothingSteps > 0 && broken) smoothFractureFaces(*levelSet, faces, voxelSizeM, style);
    if (style.fractureRoughness > 0.0 && broken)
        roughenFractureFaces(*levelSet, faces, voxelSizeM, style.fractureRoughness, style.subdivisions);
    return levelSet->treePtr();
}

openvdb::Coord voxelBlockOf(const openvdb::Coord& voxel)
{
    return openvdb::Coord(voxel.x() >> kVoxelBlockLog2, voxel.y() >> kVoxelBlockLog2, voxel.z() >> kVoxelBlockLog2);
}

namespace {

static_assert(FloatLeaf::LOG2DIM == kVoxelBlockLog2, "a block of voxels is a leaf of a voxel tree");

bool sameLeaf(const FloatLeaf& a, const FloatLeaf& b)
{
    if (a.getValueMask() != b.getValueMask()) return false;
    for (auto it = a.cbeginValueOn(); it; ++it)
        if (b.getValue(it.pos()) != *it) return false;
    return true;
}

/// The samples a block's edge spans (a multiple of the level set's leaf edge).
int blockEdgeSamples(const SurfaceStyle& style) { return style.subdivisions << kVoxelBlockLog2; }

int blocksSpanning(int samples, const SurfaceStyle& style) { return (samples + blockEdgeSamples(style) - 1) / blockEdgeSamples(style); }

/// The faces where `voxels` in the `worked` blocks meet voxels outside them, as the object's own
/// (they close the worked region's solid and neither flow nor roughen).
void appendCutFaces(const openvdb::FloatTree& voxels, const openvdb::MaskTree& worked, std::vector<VoxelFace>& faces)
{
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> solid(voxels);
    for (auto block = worked.cbeginValueOn(); block; ++block) {
        const FloatLeaf* leaf = voxels.probeConstLeaf(leafOrigin(block.getCoord()));
        if (!leaf) continue;
        for (auto v = leaf->cbeginValueOn(); v; ++v)
            for (int f = 0; f < kFaceCount; ++f) {
                const openvdb::Coord across = v.getCoord() + faceOffset(f);
                if (!worked.isValueOn(voxelBlockOf(across)) && solid.isValueOn(across)) faces.push_back({v.getCoord(), f, false});
            }
    }
}

/// Replaces the level-set leaves of the `blocks` in `to` by those (or the tiles) of `from`.
void copyBlocks(const openvdb::FloatTree& from, openvdb::FloatTree& to, const openvdb::MaskTree& blocks, const SurfaceStyle& style)
{
    const int edge = blockEdgeSamples(style), leafEdge = int(FloatLeaf::DIM);
    for (auto block = blocks.cbeginValueOn(); block; ++block) {
        // Voxel face v - 1/2 is sample k v + kSampleIndexOffset (levelSetTransform).
        const openvdb::Coord b = block.getCoord();
        const openvdb::Coord first(b.x() * edge + kSampleIndexOffset, b.y() * edge + kSampleIndexOffset, b.z() * edge + kSampleIndexOffset);
        for (int i = 0; i < edge; i += leafEdge)
            for (int j = 0; j < edge; j += leafEdge)
                for (int k = 0; k < edge; k += leafEdge) {
                    const openvdb::Coord origin = first.offsetBy(i, j, k);
                    if (const FloatLeaf* leaf = from.probeConstLeaf(origin))
                        to.addLeaf(new FloatLeaf(*leaf));
                    else
                        to.addTile(1, origin, from.getValue(origin), false);
                }
    }
}

}  // namespace

openvdb::MaskTree blocksThatDiffer(const openvdb::FloatTree& before, const openvdb::FloatTree& after)
{
    openvdb::MaskTree differ(false);
    for (auto leaf = before.cbeginLeaf(); leaf; ++leaf) {
        const FloatLeaf* other = after.probeConstLeaf(leaf->origin());
        if (!other || !sameLeaf(*leaf, *other)) differ.setValueOn(voxelBlockOf(leaf->origin()));
    }
    for (auto leaf = after.cbeginLeaf(); leaf; ++leaf)
        if (!before.probeConstLeaf(leaf->origin())) differ.setValueOn(voxelBlockOf(leaf->origin()));
    return differ;
}

UpdateReach updateReachOf(const SurfaceStyle& style)
{
    const int band = int(std::ceil(style.halfWidthSamples)), leaf = int(FloatLeaf::DIM);
    const int grownLeaves = style.smoothingSteps / kStepsPerLeaf;
    const int roughening = style.fractureRoughness > 0.0 ? leaf : 0;  // the renormalisation's stencil
    const int smoothed = style.smoothingSteps > 0 ? leaf * (kChangedLeaves + grownLeaves) : 0;
    const int smoothingHalo = style.smoothingSteps > 0 ? leaf * (kHaloLeaves + 2 * grownLeaves) : 0;
    UpdateReach reach;
    reach.rewrittenBlocks = blocksSpanning(band + smoothed + roughening, style);
    reach.workedBlocks = reach.rewrittenBlocks + blocksSpanning(band + smoothingHalo + roughening, style);
    return reach;
}

openvdb::FloatTree::Ptr updatedVoxelSurfaceLevelSet(const openvdb::FloatTree& previous, const openvdb::FloatTree& voxels,
                                                    const std::vector<VoxelFace>& faces, const openvdb::MaskTree& changedBlocks,
                                                    double voxelSizeM, const SurfaceStyle& style)
{
    const UpdateReach reach = updateReachOf(style);
    openvdb::MaskTree rewritten(changedBlocks), worked(changedBlocks);
    openvdb::tools::dilateActiveValues(rewritten, reach.rewrittenBlocks, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    openvdb::tools::dilateActiveValues(worked, reach.workedBlocks, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    // The worked blocks cost about what they would in a whole surface: past half the shape's,
    // the whole is as cheap (and exact).
    openvdb::Index64 workedWithVoxels = 0;
    for (auto block = worked.cbeginValueOn(); block; ++block) workedWithVoxels += voxels.probeConstLeaf(leafOrigin(block.getCoord())) != nullptr;
    if (2 * workedWithVoxels > voxels.leafCount()) return nullptr;
    std::vector<VoxelFace> region;
    for (const VoxelFace& f : faces)
        if (worked.isValueOn(voxelBlockOf(f.voxel))) region.push_back(f);
    appendCutFaces(voxels, worked, region);
    auto updated = std::make_shared<openvdb::FloatTree>(previous);
    if (region.empty()) {  // the worked blocks lost every voxel: nothing of the shape lies there
        copyBlocks(openvdb::FloatTree(previous.background()), *updated, rewritten, style);
        return updated;
    }
    copyBlocks(*voxelSurfaceLevelSet(region, voxelSizeM, style), *updated, rewritten, style);
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
