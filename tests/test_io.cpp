// The io stage on its own: the history, frames and PNG files read back by an independent reader
// (the HDF5 and libpng C APIs, OpenVDB's own file reader) or by spall's reader against values
// written out by hand.
#include "TestUtil.h"

#include <spall/core/Error.h>
#include <spall/output/History.h>
#include <spall/output/Png.h>
#include <spall/fracture/Fracture.h>
#include <spall/output/FragmentSurface.h>
#include <spall/output/FrameWriter.h>
#include <spall/voxel/VdbIo.h>
#include <spall/render/Render.h>

#include <gtest/gtest.h>
#include <hdf5.h>
#include <png.h>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <filesystem>
#include <map>
#include <fstream>

using namespace spall;

namespace {

/// A fresh scratch directory per test.
std::string scratch(const std::string& name)
{
    const auto dir = std::filesystem::temp_directory_path() / ("spall_io_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

BodyRow bodyRow(int64_t id, double x)
{
    BodyRow b;
    b.id = id;
    b.positionM = Eigen::Vector3d(x, 2 * x, 3 * x);
    b.linearVelocityMS = Eigen::Vector3d(1, 0, -x);
    b.massKg = 1.5 * id;
    b.voxelCount = id;
    return b;
}

}  // namespace

TEST(History, FramesBodiesAndEventsReadBackAsWritten)
{
    const std::string path = scratch("history") + "/history.h5";
    {
        HistoryWriter w(path, HistoryHeader{0.1, 42, "{}", {{Eigen::Vector3d(0, -4, 0), 20.0, 0.0, "surface"}}});
        FrameRow f0;
        f0.timeS = 0;
        f0.bodyCount = 1;
        w.appendFrame(f0, {bodyRow(0, 0.5)}, {}, {});
        FrameRow f1;
        f1.timeS = 1.0 / 24;
        f1.brokenLinks = 7;
        f1.bodyCount = 2;
        w.appendFrame(f1, {bodyRow(1, 1.0), bodyRow(2, 2.0)}, {FractureEvent{0.01, 0, {1, 2}}}, {});
        w.finish();
    }
    const History h = readHistory(path);
    EXPECT_TRUE(h.runComplete);
    EXPECT_EQ(h.seed, 42u);
    EXPECT_DOUBLE_EQ(h.voxelSizeM, 0.1);
    ASSERT_EQ(h.frameCount(), 2u);
    EXPECT_EQ(h.bodyOffset, (std::vector<int64_t>{0, 1, 3}));  // CSR: frame f's bodies are rows [offset[f], offset[f+1])
    EXPECT_EQ(h.bodyId, (std::vector<int64_t>{0, 1, 2}));
    EXPECT_EQ(h.brokenLinks, (std::vector<int64_t>{0, 7}));
    EXPECT_EQ(h.bodyPositionM[2], Eigen::Vector3d(2, 4, 6));
    EXPECT_EQ(h.bodyLinearVelocityMS[1], Eigen::Vector3d(1, 0, -1));
    EXPECT_DOUBLE_EQ(h.bodyMassKg[2], 3.0);
    ASSERT_EQ(h.eventTimeS.size(), 1u);
    EXPECT_EQ(h.eventParentId[0], 0);
}

TEST(History, UnfinishedRunIsMarkedAndResumeCutsLaterRows)
{
    const std::string path = scratch("resume") + "/history.h5";
    {
        HistoryWriter w(path, HistoryHeader{0.1, 1, "{}", {}});
        for (int f = 0; f < 3; ++f) {
            FrameRow row;
            row.timeS = f;
            w.appendFrame(row, {bodyRow(f, f)}, {}, {});
        }
    }  // not finished: an interrupted run
    EXPECT_FALSE(readHistory(path).runComplete);
    {
        HistoryWriter w(path, HistoryResumePoint{2, 0, 0});  // the checkpoint was after frame 1
        FrameRow row;
        row.timeS = 10;
        w.appendFrame(row, {bodyRow(9, 9)}, {}, {});
        w.finish();
    }
    const History h = readHistory(path);
    EXPECT_TRUE(h.runComplete);
    EXPECT_EQ(h.timeS, (std::vector<double>{0, 1, 10}));
    EXPECT_EQ(h.bodyId, (std::vector<int64_t>{0, 1, 9}));
}

TEST(History, OtherFormatVersionsAndOtherFilesAreRefusedNamingTheFile)
{
    const std::string dir = scratch("version");
    const std::string path = dir + "/history.h5";
    {
        HistoryWriter w(path, HistoryHeader{0.1, 1, "{}", {}});
        w.finish();
    }
    // Change the root's format_version with the HDF5 C API, as a newer spall would write it.
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t attribute = H5Aopen(file, "format_version", H5P_DEFAULT);
    const int future = kHistoryFormatVersion + 1;
    H5Awrite(attribute, H5T_NATIVE_INT, &future);
    H5Aclose(attribute);
    H5Fclose(file);
    try {
        readHistory(path);
        FAIL() << "a history of another format version was read";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("format version"), std::string::npos) << e.what();
    }
    std::ofstream(dir + "/text.h5") << "not HDF5";
    EXPECT_THROW(readHistory(dir + "/text.h5"), IoError);
}

namespace {

/// The positions of a grid's active voxel centres in the world, sorted.
std::vector<Eigen::Vector3d> sortedCentres(const std::vector<Eigen::Vector3d>& centres)
{
    std::vector<Eigen::Vector3d> out = centres;
    std::sort(out.begin(), out.end(), [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
        return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
    });
    return out;
}

std::vector<Eigen::Vector3d> worldCentres(const openvdb::FloatGrid& grid)
{
    std::vector<Eigen::Vector3d> out;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d w = grid.transform().indexToWorld(it.getCoord());
        out.emplace_back(w.x(), w.y(), w.z());
    }
    return sortedCentres(out);
}

std::vector<Eigen::Vector3d> worldCentres(const Body& body)
{
    std::vector<Eigen::Vector3d> out;
    for (auto it = body.grid->cbeginValueOn(); it; ++it) out.push_back(body.voxelWorldM(it.getCoord()));
    return sortedCentres(out);
}

/// A mesh of a level set: its volume by the divergence theorem, and whether every edge is shared
/// by exactly two polygons (a closed surface).
struct MeshCheck {
    double volumeM3 = 0.0;
    bool closed = true;
    size_t polygons = 0;
};
MeshCheck meshOf(const openvdb::FloatGrid& levelSet)
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(levelSet, points, triangles, quads, 0.0, 0.0);
    MeshCheck check;
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    auto polygon = [&](std::initializer_list<uint32_t> v) {
        const std::vector<uint32_t> ids(v);
        // Relative to one vertex of the mesh, so far from the origin no precision is lost.
        const openvdb::Vec3d o = points.front(), p0 = openvdb::Vec3d(points[ids[0]]) - o;
        for (size_t i = 1; i + 1 < ids.size(); ++i)
            check.volumeM3 += p0.dot((openvdb::Vec3d(points[ids[i]]) - o).cross(openvdb::Vec3d(points[ids[i + 1]]) - o)) / 6.0;
        for (size_t i = 0; i < ids.size(); ++i) {
            const uint32_t a = ids[i], b = ids[(i + 1) % ids.size()];
            ++edges[{std::min(a, b), std::max(a, b)}];
        }
        ++check.polygons;
    };
    for (const auto& t : triangles) polygon({t[0], t[1], t[2]});
    for (const auto& q : quads) polygon({q[0], q[1], q[2], q[3]});
    for (const auto& [edge, count] : edges) check.closed = check.closed && count == 2;
    check.volumeM3 = std::abs(check.volumeM3);
    return check;
}

}  // namespace

TEST(Frames, EachFragmentIsASolidPlacedByItsTransformAndReadByOpenVdb)
{
    initialiseOpenVdb();
    Body a = test::boxBody(2, 3, 1, 0.1, 1000.0, Eigen::Vector3d(1, 2, 3),
                           Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
    a.id = 5;
    Body b = test::boxBody(1, 1, 1, 0.1, 1000.0, Eigen::Vector3d(-1, 0, 0.5));
    b.id = 6;
    // An L: a concave edge as well as convex ones.
    Body c;
    c.id = 7;
    c.voxelSizeM = 0.1;
    c.grid = test::gridFromVoxels({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, 0.1);
    refreshDerivedData(c);
    c.motion.positionM = Eigen::Vector3d(0.3, -0.2, 1.0);
    for (int subdivisions : {2, 3, 4}) {
        const std::string dir = scratch("frames" + std::to_string(subdivisions));
        OutputSettings settings;
        settings.levelSetSubdivisions = subdivisions;
        FrameWriter writer(dir, settings);
        const std::string path = writer.write({3, 0.125}, {a, b, c});
        EXPECT_EQ(path, FrameWriter::framePath(dir, 3));
        openvdb::io::File file(path);
        file.open();
        for (const Body* body : {&a, &b, &c}) {
            const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fragment_" + std::to_string(body->id)));
            ASSERT_TRUE(grid) << body->id;
            EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
            // The mesh every reader makes (OpenVDB's volume-to-mesh) is closed and, where every
            // edge is convex, the voxels' surface to rounding; a concave edge is bevelled outward
            // within a sample of it (docs/file-formats.md).
            const MeshCheck mesh = meshOf(*grid);
            const double voxelVolume = body->mass.voxelCount * std::pow(body->voxelSizeM, 3);
            EXPECT_TRUE(mesh.closed) << body->id;
            const double bound = body == &c ? (subdivisions >= 3 ? 0.10 : 0.15) : 1e-5;
            EXPECT_NEAR(mesh.volumeM3, voxelVolume, bound * voxelVolume) << body->id << " at " << subdivisions << " samples per voxel";
            if (body == &c) std::printf("an L of 4 voxels at %d samples per voxel: mesh volume / voxel volume %.4f\n", subdivisions, mesh.volumeM3 / voxelVolume);
            // Back to voxels: each one's centre in the world, through the file's transform, is the body's.
            const auto voxels = voxelsOfLevelSet(*grid, subdivisions);
            const auto fromFile = worldCentres(*voxels), fromBody = worldCentres(*body);
            ASSERT_EQ(fromFile.size(), fromBody.size()) << body->id;
            for (size_t i = 0; i < fromFile.size(); ++i) EXPECT_LT((fromFile[i] - fromBody[i]).norm(), 1e-9) << body->id;
        }
        EXPECT_TRUE(file.hasGrid("density"));
        EXPECT_FALSE(file.hasGrid("v")) << "velocity only on request";
        EXPECT_FALSE(file.hasGrid("fracture_faces_5")) << "an unbroken body has no fracture surface";
        file.close();
        for (const auto& entry : std::filesystem::directory_iterator(dir))
            EXPECT_EQ(entry.path().string().find("partial"), std::string::npos) << "a temporary was left: " << entry.path();
    }
}

TEST(Frames, TheDebrisLevelSetHoldsEveryPieceWhereItsOwnGridPutsIt)
{
    initialiseOpenVdb();
    // Two turned pieces and one at rest, written with output.debris_level_set and the film's
    // first frame: one world-aligned grid whose mesh holds the pieces' volume, less what
    // interpolating the distance between samples takes off each edge and corner (8 % of these
    // pieces one and two voxels across; 1.5 % of the default scene's bricks, 4 % of a wall of
    // single voxels that tests/cli_integration.sh checks within 6 %), inside where each piece's
    // centre is, outside
    // between them.
    Body a = test::boxBody(4, 3, 2, 0.1, 1000.0, Eigen::Vector3d(1, 2, 3),
                           Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
    a.id = 5;
    Body b = test::boxBody(2, 2, 2, 0.1, 1000.0, Eigen::Vector3d(-1, 0, 0.5), Eigen::Quaterniond(Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitZ())));
    b.id = 6;
    Body c = test::boxBody(3, 1, 1, 0.1, 1000.0, Eigen::Vector3d(0.2, -1, 0.05));
    c.id = 7;
    OutputSettings settings;
    settings.debrisLevelSet = true;
    settings.firstFrame = 1001;
    const std::string dir = scratch("debris-level-set");
    FrameWriter writer(dir, settings);
    writer.write({0, 0.0, 24.0}, {a, b, c});
    const std::string path = writer.write({2, 2.0 / 24.0, 24.0}, {a, b, c});  // b and c at rest: their resampling is kept
    EXPECT_EQ(path, FrameWriter::framePath(dir, 1003));
    openvdb::io::File file(path);
    file.open();
    const openvdb::MetaMap::Ptr meta = file.getMetadata();
    EXPECT_EQ(meta->metaValue<int32_t>("frame"), 1003);
    EXPECT_EQ(meta->metaValue<int32_t>("first_frame"), 1001);
    EXPECT_DOUBLE_EQ(meta->metaValue<double>("frame_rate_hz"), 24.0);
    const auto debris = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("debris"));
    ASSERT_TRUE(debris);
    EXPECT_EQ(debris->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_EQ(debris->metaValue<int32_t>("frame"), 1003);
    file.close();
    const MeshCheck mesh = meshOf(*debris);
    double voxelVolume = 0.0;
    for (const Body* body : {&a, &b, &c}) voxelVolume += body->mass.voxelCount * std::pow(body->voxelSizeM, 3);
    EXPECT_TRUE(mesh.closed);
    EXPECT_NEAR(mesh.volumeM3, voxelVolume, 0.12 * voxelVolume);
    std::printf("debris level set of 3 pieces, 2 turned: mesh volume / voxel volume %.4f\n", mesh.volumeM3 / voxelVolume);
    const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> at(*debris);
    for (const Body* body : {&a, &b, &c}) {
        const Eigen::Vector3d centre = body->motion.positionM;
        EXPECT_LT(at.wsSample(openvdb::Vec3d(centre.x(), centre.y(), centre.z())), 0.0f) << body->id;
    }
    EXPECT_GT(at.wsSample(openvdb::Vec3d(0.0, 0.0, 1.5)), 0.0f) << "between the pieces";
}

namespace {

/// The level set a frame writes for `body` (its id must be 1), its fracture surface smoothed by
/// `steps` steps, written under `name` in the scratch directory.
openvdb::FloatGrid::Ptr writtenLevelSet(const Body& body, int steps, const std::string& name)
{
    OutputSettings settings;
    settings.fractureSmoothingSteps = steps;
    FrameWriter writer(scratch(name + std::to_string(steps)), settings);
    openvdb::io::File file(writer.write({0, 0.0}, {body}));
    file.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fragment_1"));
    file.close();
    return grid;
}

}  // namespace

TEST(Frames, SmoothingRoundsTheCracksStaircaseAndLeavesTheObjectsOwnSurface)
{
    initialiseOpenVdb();
    // A block 8 x 4 x 9 voxels broken along a 45-degree staircase (voxel column x breaks between
    // z = x and x + 1): the lower piece's top is a staircase whose area is sqrt(2) times that of
    // the plane it steps along. Smoothed, its surface comes toward the plane's area (half the
    // excess at least), its volume stays its voxels', and the object's own faces further than a
    // voxel from the crack stay where they were (to 1e-5 of a voxel).
    Body block = test::boxBody(8, 4, 9, 0.1, 1000.0);
    auto acc = block.grid->getAccessor();
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 4; ++y) {
            ASSERT_TRUE(breakLink(acc, openvdb::Coord(x, y, x), kPosZ));  // the step's tread
            if (x < 7) {
                ASSERT_TRUE(breakLink(acc, openvdb::Coord(x, y, x + 1), kPosX));  // its riser
            }
        }
    std::vector<Body> halves = splitBody(block);
    ASSERT_EQ(halves.size(), 2u);
    Body& lower = halves[0].grid->tree().isValueOn(openvdb::Coord(0, 0, 0)) ? halves[0] : halves[1];
    lower.id = 1;
    const auto staircase = writtenLevelSet(lower, 0, "smoothing"), smooth = writtenLevelSet(lower, 4, "smoothing");
    const SurfaceMesh before = meshLevelSet(*staircase), after = meshLevelSet(*smooth);
    const double h = lower.voxelSizeM, voxelVolume = lower.mass.voxelCount * std::pow(h, 3);
    const double excessM2 = (std::sqrt(2.0) - 1.0) * 8.0 * 4.0 * h * h;  // the staircase's area over the plane's
    EXPECT_NEAR(std::abs(after.signedVolumeM3()), voxelVolume, 0.02 * voxelVolume);
    EXPECT_LT(after.areaM2(), before.areaM2() - 0.5 * excessM2);
    EXPECT_GT(after.areaM2(), before.areaM2() - excessM2) << "smoother than the plane itself";
    std::printf("a 45-degree staircase crack smoothed: area %.4f -> %.4f m2 (the plane: %.4f less), volume x %.4f\n", before.areaM2(),
                after.areaM2(), excessM2, std::abs(after.signedVolumeM3()) / voxelVolume);
    // Own faces a voxel or more from any broken face: their samples are untouched but for rounding.
    const auto samples = staircase->getConstAccessor(), smoothed = smooth->getConstAccessor();
    const openvdb::math::Transform::Ptr toVoxels = voxelTransformOf(staircase->transform(), 3);
    size_t compared = 0;
    for (auto it = staircase->cbeginValueOn(); it; ++it) {
        if (std::abs(*it) > 0.25 * h) continue;  // near the surface
        const openvdb::Vec3d voxel = toVoxels->worldToIndex(staircase->indexToWorld(it.getCoord()));
        if (voxel.z() < voxel.x() - 0.5 - 2.0) {  // below the staircase's lowest step by over a voxel
            EXPECT_NEAR(smoothed.getValue(it.getCoord()), *it, 1e-5 * h) << it.getCoord();  // float rounding in the flow's renormalisation
            ++compared;
        }
    }
    EXPECT_GT(compared, 100u);
}

TEST(Frames, SmoothingChangesTheSurfaceOnlyNearTheCracks)
{
    initialiseOpenVdb();
    // A block 30 x 4 x 9 voxels whose end x < 8 broke off along a 45-degree staircase. The flow
    // works on the leaves near the crack alone: the rest of the level set, the block's far corners
    // and edges included, is the unsmoothed one exactly (a flow over the whole band rounded a
    // wall's corners by a quarter of a voxel: its renormalisation does not keep a corner's
    // distances), and the solid still holds its voxels' volume.
    Body block = test::boxBody(30, 4, 9, 0.1, 1000.0);
    auto acc = block.grid->getAccessor();
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 4; ++y) {
            ASSERT_TRUE(breakLink(acc, openvdb::Coord(x, y, 7 - x), kPosX));
            ASSERT_TRUE(breakLink(acc, openvdb::Coord(x, y, 7 - x), kPosZ));
        }
    std::vector<Body> parts = splitBody(block);
    ASSERT_EQ(parts.size(), 2u);
    Body& rest = parts[0].mass.voxelCount > parts[1].mass.voxelCount ? parts[0] : parts[1];
    rest.id = 1;
    const auto staircase = writtenLevelSet(rest, 0, "smoothing-near"), smooth = writtenLevelSet(rest, 4, "smoothing-near");
    const double h = rest.voxelSizeM;
    EXPECT_NEAR(std::abs(meshLevelSet(*smooth).signedVolumeM3()), rest.mass.voxelCount * std::pow(h, 3), 0.01 * rest.mass.voxelCount * std::pow(h, 3));
    const openvdb::math::Transform::Ptr toVoxels = voxelTransformOf(staircase->transform(), 3);
    const auto smoothed = smooth->getConstAccessor();
    size_t far = 0, changedNear = 0;
    for (auto it = staircase->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d voxel = toVoxels->worldToIndex(staircase->indexToWorld(it.getCoord()));
        if (voxel.x() >= 16.0) {  // over 8 voxels from the staircase, which ends at x = 8
            EXPECT_EQ(smoothed.getValue(it.getCoord()), *it) << it.getCoord();
            ++far;
        } else if (std::abs(smoothed.getValue(it.getCoord()) - *it) > 0.01 * h) {
            ++changedNear;
        }
    }
    EXPECT_GT(far, 1000u);
    EXPECT_GT(changedNear, 100u) << "the crack was smoothed";
}

namespace {

/// The `fragment_1` level set of a frame file.
openvdb::FloatGrid::Ptr readFragment(const std::string& path)
{
    openvdb::io::File file(path);
    file.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fragment_1"));
    file.close();
    return grid;
}

/// The largest part of `body` once the links across a 45-degree staircase broke: above and to +x of
/// each of `steps` voxels from `corner` stepping along +x and -z.
Body largestPartAfterStaircase(const Body& body, const openvdb::Coord& corner, int steps)
{
    Body copy = body;
    copy.grid = body.grid->deepCopy();
    auto acc = copy.grid->getAccessor();
    const int ny = body.indexBounds.dim().y();
    for (int s = 0; s < steps; ++s)
        for (int y = 0; y < ny; ++y) {
            const openvdb::Coord v = corner.offsetBy(s, y, -s);
            breakLink(acc, v, kPosX);
            breakLink(acc, v, kPosZ);
        }
    refreshDerivedData(copy);
    std::vector<Body> parts = splitBody(copy);
    Body& largest = *std::max_element(parts.begin(), parts.end(), [](const Body& a, const Body& b) { return a.mass.voxelCount < b.mass.voxelCount; });
    largest.id = 1;
    return largest;
}

/// How two level sets' values differ over both's active samples: the greatest difference (unit:
/// m) and the fraction of samples that differ by over `notableM`.
struct LevelSetDifference {
    double largestM = 0.0;
    double notableFraction = 0.0;
};
LevelSetDifference differenceOf(const openvdb::FloatGrid& a, const openvdb::FloatGrid& b, double notableM)
{
    LevelSetDifference d;
    size_t samples = 0, notable = 0;
    const auto compare = [&](const openvdb::FloatGrid& first, const openvdb::FloatGrid& second) {
        const auto other = second.getConstAccessor();
        for (auto it = first.cbeginValueOn(); it; ++it) {
            const double difference = std::abs(double(*it) - double(other.getValue(it.getCoord())));
            d.largestM = std::max(d.largestM, difference);
            notable += difference > notableM;
            ++samples;
        }
    };
    compare(a, b);
    compare(b, a);
    d.notableFraction = double(notable) / double(std::max<size_t>(samples, 1));
    return d;
}

}  // namespace

TEST(Frames, APieceThatCracksFurtherHasItsSurfaceUpdatedNearTheNewCracksAsIfMadeWhole)
{
    initialiseOpenVdb();
    // A slab 64 x 16 x 48 voxels shown in three frames as it loses a corner,
    // then a second corner at the far end, the piece keeping its id (as showPieces does). A
    // writer that saw the earlier frames updates the surface near the new cracks; it must be the
    // level set a fresh writer makes whole: the same to the bit unsmoothed; smoothed,
    // within 5 % of a voxel but at a few samples where a crack meets the object's own faces (under
    // 0.1 % of samples, by under a fifth of a voxel); its volume its voxels'.
    const Body slab = [] {
        Body b = test::boxBody(64, 16, 48, 0.1, 1000.0);
        b.id = 1;
        return b;
    }();
    const Body oneCorner = largestPartAfterStaircase(slab, openvdb::Coord(0, 0, 9), 10);
    const Body twoCorners = largestPartAfterStaircase(oneCorner, openvdb::Coord(52, 0, 47), 12);
    ASSERT_LT(twoCorners.mass.voxelCount, oneCorner.mass.voxelCount);
    ASSERT_LT(oneCorner.mass.voxelCount, slab.mass.voxelCount);
    const double h = slab.voxelSizeM;
    for (const int steps : {0, 4}) {
        OutputSettings settings;
        settings.fractureSmoothingSteps = steps;
        const std::string name = "updated-surface" + std::to_string(steps);
        FrameWriter following(scratch(name), settings);
        following.write({0, 0.0}, {slab});
        following.write({1, 0.0}, {oneCorner});
        const auto updated = readFragment(following.write({2, 0.0}, {twoCorners}));
        EXPECT_EQ(following.surfacesUpdated(), 2) << "each crack's frame updates the last surface";
        FrameWriter fresh(scratch(name + "-whole"), settings);
        const auto whole = readFragment(fresh.write({2, 0.0}, {twoCorners}));
        EXPECT_EQ(fresh.surfacesUpdated(), 0);
        const LevelSetDifference difference = differenceOf(*updated, *whole, 0.05 * h);
        std::printf("smoothing %d steps: a surface updated twice against one made whole: %.2e voxels at most, %.4f %% of samples by over 5 %% of one\n",
                    steps, difference.largestM / h, 100.0 * difference.notableFraction);
        if (steps == 0) {
            EXPECT_EQ(difference.largestM, 0.0);
            EXPECT_EQ(updated->activeVoxelCount(), whole->activeVoxelCount());
        } else {
            // The volume is restored over the remade region, not the whole, and the flow's
            // renormalisation where a crack meets the object's own faces depends on the region it
            // works on: a few samples there differ by up to a twentieth of a voxel.
            EXPECT_LT(difference.largestM, 0.2 * h);
            EXPECT_LT(difference.notableFraction, 0.001);
        }
        const double voxelVolumeM3 = twoCorners.mass.voxelCount * std::pow(h, 3);
        EXPECT_NEAR(std::abs(meshLevelSet(*updated).signedVolumeM3()), voxelVolumeM3, 0.005 * voxelVolumeM3);
    }
}

TEST(Frames, FractureRoughnessMovesBrokenFacesOnlyAndKeepsTheSolid)
{
    initialiseOpenVdb();
    // A 6 x 6 x 4 block split between its layers z = 1 and z = 2: the lower half's top is fracture
    // surface (36 faces), its bottom and sides are the object's own surface.
    Body block = test::boxBody(6, 6, 4, 0.1, 1000.0);
    auto acc = block.grid->getAccessor();
    for (int x = 0; x < 6; ++x)
        for (int y = 0; y < 6; ++y) ASSERT_TRUE(breakLink(acc, openvdb::Coord(x, y, 1), kPosZ));
    std::vector<Body> halves = splitBody(block);
    ASSERT_EQ(halves.size(), 2u);
    Body& lower = halves[0].grid->tree().isValueOn(openvdb::Coord(0, 0, 0)) ? halves[0] : halves[1];
    lower.id = 1;
    constexpr double roughness = 0.2;
    constexpr int k = 4;
    OutputSettings settings;
    settings.levelSetSubdivisions = k;
    settings.fractureRoughnessVoxels = roughness;
    FrameWriter writer(scratch("roughness"), settings);
    openvdb::io::File file(writer.write({0, 0.0}, {lower}));
    file.open();
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fragment_1"));
    const MeshCheck check = meshOf(*grid);
    const double voxelVolume = lower.mass.voxelCount * std::pow(lower.voxelSizeM, 3);
    EXPECT_TRUE(check.closed);
    EXPECT_NEAR(check.volumeM3, voxelVolume, 0.03 * voxelVolume) << "the noise moves faces in and out about equally";

    // Mesh vertices in the body's voxel units (voxel centres at integers; the fracture plane z = 1.5).
    const auto voxelMap = voxelTransformOf(grid->transform(), k);
    double topSquares = 0.0, topMax = 0.0, ownMax = 0.0;
    int topCount = 0, ownCount = 0;
    for (const Eigen::Vector3d& w : meshLevelSet(*grid).pointsM) {
        const openvdb::Vec3d v = voxelMap->worldToIndex(openvdb::Vec3d(w.x(), w.y(), w.z()));
        const bool inner = v.x() > 0.5 && v.x() < 4.5 && v.y() > 0.5 && v.y() < 4.5;  // a voxel in from the sides
        if (inner && v.z() > 1.0) {
            topSquares += std::pow(v.z() - 1.5, 2);
            topMax = std::max(topMax, std::abs(v.z() - 1.5));
            ++topCount;
        } else if (v.z() < 0.9) {  // the bottom and the sides' lower parts, half a voxel from any break
            const double toOwnFace = std::min({std::abs(v.z() + 0.5), std::abs(v.x() + 0.5), std::abs(v.x() - 5.5), std::abs(v.y() + 0.5),
                                               std::abs(v.y() - 5.5)});
            ownMax = std::max(ownMax, toOwnFace);
            ++ownCount;
        }
    }
    ASSERT_GT(topCount, 100);
    ASSERT_GT(ownCount, 100);
    const double topRms = std::sqrt(topSquares / topCount);
    std::printf("fracture roughness %.2f voxels: fracture faces move by %.3f rms, %.3f at most; own faces by %.4f at most (voxels)\n",
                roughness, topRms, topMax, ownMax);
    EXPECT_GT(topRms, 0.2 * roughness) << "the broken face is not rough";
    EXPECT_LT(topMax, 1.1 * roughness) << "the noise exceeds its amplitude";
    EXPECT_LT(ownMax, 0.01) << "the object's own surface moved";
    // Every voxel's centre stays on its side: the preview sees the same voxels.
    EXPECT_EQ(voxelsOfLevelSet(*grid, k)->activeVoxelCount(), openvdb::Index64(lower.mass.voxelCount));
}

TEST(Frames, FractureFacesAreTheFacesWhoseLinksBroke)
{
    initialiseOpenVdb();
    const std::vector<Body> halves = test::barBrokenInTwo(test::boxBody(4, 1, 1, 0.1, 1000.0), 10);
    ASSERT_EQ(halves.size(), 2u);
    FrameWriter writer(scratch("fracture-faces"), OutputSettings{});
    openvdb::io::File file(writer.write({0, 0.0}, halves));
    file.open();
    for (const Body& half : halves) {
        const auto faces = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fracture_faces_" + std::to_string(half.id)));
        ASSERT_TRUE(faces) << half.id;
        ASSERT_EQ(faces->activeVoxelCount(), 1u);
        const auto it = faces->cbeginValueOn();
        const bool left = half.grid->tree().isValueOn(openvdb::Coord(1, 0, 0));
        EXPECT_EQ(int(*it), 1 << (left ? kPosX : kNegX)) << half.id;
        // The marked voxel, through the grid's transform, is the one beside the break.
        const openvdb::Vec3d w = faces->transform().indexToWorld(it.getCoord());
        EXPECT_LT((Eigen::Vector3d(w.x(), w.y(), w.z()) - half.voxelWorldM(openvdb::Coord(left ? 1 : 2, 0, 0))).norm(), 1e-9);
    }
}

TEST(Frames, VelocityGridHoldsTheRigidVelocityAndFogStaysAvailable)
{
    initialiseOpenVdb();
    Body spinning = test::boxBody(3, 1, 1, 0.1, 1000.0, Eigen::Vector3d(0, 0, 1));
    spinning.id = 1;
    spinning.motion.linearVelocityMS = Eigen::Vector3d(1, 2, 3);
    spinning.motion.angularVelocityRadS = Eigen::Vector3d(0, 0, 10);
    OutputSettings settings;
    settings.velocityGrid = true;
    settings.fragmentGrids = FragmentGrids::Fog;
    FrameWriter writer(scratch("velocity"), settings);
    openvdb::io::File file(writer.write({0, 0.0}, {spinning}));
    file.open();
    const auto v = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid("v"));
    ASSERT_TRUE(v);
    EXPECT_EQ(v->activeVoxelCount(), 3u);
    for (auto it = v->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d x = v->transform().indexToWorld(it.getCoord());
        // v + ω × r by hand: ω = 10 ẑ, r = (x, y, z - 1) from the centre of mass.
        const Eigen::Vector3d expected(1 - 10 * x.y(), 2 + 10 * x.x(), 3);
        EXPECT_LT((Eigen::Vector3d((*it)[0], (*it)[1], (*it)[2]) - expected).norm(), 1e-5);
    }
    const auto fog = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fragment_1"));
    ASSERT_TRUE(fog);
    EXPECT_EQ(fog->getGridClass(), openvdb::GRID_FOG_VOLUME);
    EXPECT_EQ(fog->activeVoxelCount(), 3u);
    EXPECT_EQ(file.getMetadata()->metaValue<std::string>("fragment_grids"), "fog");
}

TEST(Png, PixelsReadBackThroughLibpngAndAFailedWriteLeavesNothing)
{
    const std::string dir = scratch("png");
    Image image(7, 5, Rgb{10, 20, 30});
    image.set(3, 2, Rgb{255, 0, 128});
    writePng(dir + "/a.png", image);
    png_image read{};
    read.version = PNG_IMAGE_VERSION;
    ASSERT_TRUE(png_image_begin_read_from_file(&read, (dir + "/a.png").c_str()));
    read.format = PNG_FORMAT_RGB;
    std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(read));
    ASSERT_TRUE(png_image_finish_read(&read, nullptr, pixels.data(), 0, nullptr));
    EXPECT_EQ(read.width, 7u);
    EXPECT_EQ(read.height, 5u);
    auto at = [&](int x, int y) { return std::array<int, 3>{pixels[3 * (y * 7 + x)], pixels[3 * (y * 7 + x) + 1], pixels[3 * (y * 7 + x) + 2]}; };
    EXPECT_EQ(at(3, 2), (std::array<int, 3>{255, 0, 128}));
    EXPECT_EQ(at(0, 0), (std::array<int, 3>{10, 20, 30}));
    EXPECT_THROW(writePng(dir + "/missing/b.png", image), IoError);
    EXPECT_FALSE(std::filesystem::exists(dir + "/missing"));
}

namespace {

/// Rows of a plot where a pixel of `colour` lies in column x, top first.
std::vector<int> rowsOfColour(const Image& image, int x, Rgb colour)
{
    std::vector<int> rows;
    for (int y = 0; y < image.height(); ++y) {
        const Rgb c = image.get(x, y);
        if (c.r == colour.r && c.g == colour.g && c.b == colour.b) rows.push_back(y);
    }
    return rows;
}

bool saturated(Rgb c) { return std::max({c.r, c.g, c.b}) - std::min({c.r, c.g, c.b}) > 60; }

}  // namespace

TEST(Plot, ALogAxisSetsALimitFarBelowTheDataApartFromIt)
{
    // A density falling from 7 to 0.015 per m2 over 10 m and a limit of 1 per 55.7 m2 (DDESB's
    // hazardous density): where the density is 30 times the limit, the two lines must be a
    // tenth of the plot's height apart (on a linear axis they are 7 %).
    PlotSeries density{"density", {}, {}}, limit{"limit", {0, 10}, {1 / 55.7, 1 / 55.7}};
    for (int i = 0; i <= 10; ++i) {
        density.x.push_back(i);
        density.y.push_back(7.0 * std::pow(0.015 / 7.0, i / 10.0));
    }
    const double xAt30Times = 10 * std::log(30 / 55.7 / 7.0) / std::log(0.015 / 7.0);
    const int width = 900, height = 560, left = 110, right = width - 30;
    const int column = int(left + xAt30Times / 10 * (right - left));
    for (const PlotScale scale : {PlotScale::LogY, PlotScale::Linear}) {
        const Image plot = plotSeries({density, limit}, "x", "y", "", scale, width, height);
        const std::vector<int> densityRows = rowsOfColour(plot, column, Rgb{30, 90, 200}), limitRows = rowsOfColour(plot, column, Rgb{200, 60, 40});
        ASSERT_FALSE(densityRows.empty());
        ASSERT_FALSE(limitRows.empty());
        const double apart = double(limitRows.front() - densityRows.back()) / (height - 120);
        if (scale == PlotScale::LogY) EXPECT_GT(apart, 0.1);
        else EXPECT_LT(apart, 0.1) << "the linear axis should crowd them (the reason for the log axis)";
    }
}

TEST(Plot, TheLegendHidesAlmostNoneOfTheLines)
{
    // Lines through all four corners but one: the legend goes to the free one.
    PlotSeries rising{"rising line", {0, 10}, {0, 10}}, falling{"falling line and its long name", {0, 5, 10}, {10, 5, 10}};
    PlotSeries risingUnnamed{"", rising.x, rising.y}, fallingUnnamed{"", falling.x, falling.y};
    const Image withLegend = plotSeries({rising, falling}, "x", "y", "", PlotScale::Linear);
    const Image without = plotSeries({risingUnnamed, fallingUnnamed}, "x", "y", "", PlotScale::Linear);
    int linePixels = 0, hidden = 0;
    for (int y = 0; y < without.height(); ++y)
        for (int x = 0; x < without.width(); ++x) {
            if (!saturated(without.get(x, y))) continue;
            ++linePixels;
            const Rgb a = without.get(x, y), b = withLegend.get(x, y);
            hidden += a.r != b.r || a.g != b.g || a.b != b.b;
        }
    ASSERT_GT(linePixels, 1000);
    EXPECT_LT(hidden, linePixels / 100) << hidden << " of " << linePixels << " line pixels hidden by the legend";
}

TEST(Render, TheCameraFramesTheDebrisNotTheEmptyGround)
{
    initialiseOpenVdb();
    // A 2 x 0.3 x 1.5 m wall, then the same with one voxel thrown 50 m away: the wall fills the
    // picture either way (a fifth of its pixels or more), the far voxel is left out of frame.
    const RenderSettings settings{320, 180, 0.0, {}};
    Body wall = test::boxBody(20, 3, 15, 0.1, 1000.0, Eigen::Vector3d(0, 0, 0.75));
    Body stray = test::boxBody(1, 1, 1, 0.1, 1000.0, Eigen::Vector3d(50, 20, 0.05));
    stray.id = 1;
    for (const std::vector<Body>& bodies : {std::vector<Body>{wall}, std::vector<Body>{wall, stray}}) {
        const auto fragments = fragmentsOf(bodies);
        const Camera camera = frameCamera({fragments}, settings);
        const Image picture = renderFragments(fragments, camera, settings), ground = renderFragments({}, camera, settings);
        int covered = 0;
        for (int y = 0; y < settings.height; ++y)
            for (int x = 0; x < settings.width; ++x) {
                const Rgb a = picture.get(x, y), b = ground.get(x, y);
                covered += a.r != b.r || a.g != b.g || a.b != b.b;
            }
        const double fraction = double(covered) / (settings.width * settings.height);
        EXPECT_GT(fraction, 0.2) << bodies.size() << " bodies: the wall covers " << fraction << " of the picture";
    }
}

TEST(Render, ABodyInFrontOfTheCameraCoversTheMiddleOfThePicture)
{
    initialiseOpenVdb();
    // A 1 m cube at the origin seen from 10 m along -y, level with it: it fills the middle of the
    // picture (its half-width subtends 2.9 degrees of a 40 degree view: about 7 % of the height).
    const std::vector<Body> bodies{test::boxBody(10, 10, 10, 0.1, 1000.0, Eigen::Vector3d(0, 0, 0.5))};
    const RenderSettings settings{200, 200, -10.0, {}};  // the ground far below, out of view
    Camera camera;
    camera.eyeM = Eigen::Vector3d(0, -10, 0.5);
    camera.targetM = Eigen::Vector3d(0, 0, 0.5);
    const Image image = renderFragments(fragmentsOf(bodies), camera, settings);
    const Rgb centre = image.get(100, 100), corner = image.get(2, 2);
    EXPECT_FALSE(centre.r == corner.r && centre.g == corner.g && centre.b == corner.b) << "the cube is not drawn in the middle";
    // 14 % of the width either side of the middle is cube, well beyond it is not.
    const Rgb inside = image.get(100 + 10, 100), outside = image.get(100 + 40, 100);
    EXPECT_TRUE(inside.r == centre.r && inside.g == centre.g && inside.b == centre.b);
    EXPECT_FALSE(outside.r == centre.r && outside.g == centre.g && outside.b == centre.b);
}

TEST(Render, AChargeIsDrawnWhereItIsUnlessABodyHidesIt)
{
    initialiseOpenVdb();
    // The 1 m cube of the test above, seen from 10 m along -y: a charge 2 m in front of it and
    // 0.3 m to the right is drawn there in the charge colour; one behind the cube's middle is hidden.
    const std::vector<Body> bodies{test::boxBody(10, 10, 10, 0.1, 1000.0, Eigen::Vector3d(0, 0, 0.5))};
    RenderSettings settings{200, 200, -10.0, {Eigen::Vector3d(0.3, -2.0, 0.5), Eigen::Vector3d(0, 3.0, 0.5)}};
    Camera camera;
    camera.eyeM = Eigen::Vector3d(0, -10, 0.5);
    camera.targetM = Eigen::Vector3d(0, 0, 0.5);
    const Image image = renderFragments(fragmentsOf(bodies), camera, settings);
    // 0.3 m right at 8 m: atan(0.3/8) of a 40 degree view of 200 pixels, about 10 pixels right.
    const double focal = 100.0 / std::tan(20.0 * M_PI / 180.0);
    const int x = int(100 + focal * 0.3 / 8.0);
    const auto isCharge = [](Rgb c) { return c.r == kChargeColour.r && c.g == kChargeColour.g && c.b == kChargeColour.b; };
    EXPECT_TRUE(isCharge(image.get(x, 100))) << "the charge in front is not drawn where it is";
    EXPECT_FALSE(isCharge(image.get(100, 100))) << "the charge behind the cube shows through it";
    settings.chargesM.clear();
    EXPECT_FALSE(isCharge(renderFragments(fragmentsOf(bodies), camera, settings).get(x, 100)));
}


