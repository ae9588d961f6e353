// The io stage on its own: the history, frames and PNG files read back by an independent reader
// (the HDF5 and libpng C APIs, OpenVDB's own file reader) or by spall's reader against values
// written out by hand.
#include "TestUtil.h"

#include <spall/core/Error.h>
#include <spall/io/History.h>
#include <spall/io/Png.h>
#include <spall/io/VdbIo.h>
#include <spall/render/Render.h>

#include <gtest/gtest.h>
#include <hdf5.h>
#include <png.h>

#include <filesystem>
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

TEST(Frames, EachFragmentIsPlacedByItsTransformAndReadByOpenVdb)
{
    initialiseOpenVdb();
    const std::string dir = scratch("frames");
    Body a = test::boxBody(2, 3, 1, 0.1, 1000.0, Eigen::Vector3d(1, 2, 3),
                           Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
    a.id = 5;
    Body b = test::boxBody(1, 1, 1, 0.1, 1000.0, Eigen::Vector3d(-1, 0, 0.5));
    b.id = 6;
    FrameWriter writer(dir, true);
    const std::string path = writer.write({3, 0.125}, {a, b});
    EXPECT_EQ(path, FrameWriter::framePath(dir, 3));
    openvdb::io::File file(path);
    file.open();
    for (const Body* body : {&a, &b}) {
        const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("fragment_" + std::to_string(body->id)));
        ASSERT_TRUE(grid) << body->id;
        EXPECT_EQ(static_cast<int64_t>(grid->activeVoxelCount()), body->mass.voxelCount);
        // Every active voxel's centre in the world, through the file's transform, is the body's.
        std::vector<Eigen::Vector3d> fromFile, fromBody;
        for (auto it = grid->cbeginValueOn(); it; ++it) {
            const openvdb::Vec3d w = grid->transform().indexToWorld(it.getCoord());
            fromFile.emplace_back(w.x(), w.y(), w.z());
        }
        for (auto it = body->grid->cbeginValueOn(); it; ++it) fromBody.push_back(body->voxelWorldM(it.getCoord()));
        ASSERT_EQ(fromFile.size(), fromBody.size());
        auto order = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) { return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3); };
        std::sort(fromFile.begin(), fromFile.end(), order);
        std::sort(fromBody.begin(), fromBody.end(), order);
        for (size_t i = 0; i < fromFile.size(); ++i) EXPECT_LT((fromFile[i] - fromBody[i]).norm(), 1e-9) << body->id;
    }
    EXPECT_TRUE(file.hasGrid("density"));
    file.close();
    for (const auto& entry : std::filesystem::directory_iterator(dir))
        EXPECT_EQ(entry.path().string().find("partial"), std::string::npos) << "a temporary was left: " << entry.path();
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

TEST(Render, ABodyInFrontOfTheCameraCoversTheMiddleOfThePicture)
{
    initialiseOpenVdb();
    // A 1 m cube at the origin seen from 10 m along -y, level with it: it fills the middle of the
    // picture (its half-width subtends 2.9 degrees of a 40 degree view: about 7 % of the height).
    const std::vector<Body> bodies{test::boxBody(10, 10, 10, 0.1, 1000.0, Eigen::Vector3d(0, 0, 0.5))};
    const RenderSettings settings{200, 200, -10.0};  // the ground far below, out of view
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
