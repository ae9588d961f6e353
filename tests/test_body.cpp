#include "TestUtil.h"

#include <spall/voxel/Components.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

using namespace spall;
using openvdb::Coord;

TEST(MassProperties, BoxMatchesClosedForm)
{
    const int nx = 6, ny = 4, nz = 10;
    const double h = 0.05, rho = 2000.0;
    const MassProperties mp = computeMassProperties(*test::boxGrid(nx, ny, nz, h), h, rho);
    const double a = nx * h, b = ny * h, c = nz * h, m = rho * a * b * c;
    EXPECT_EQ(mp.voxelCount, nx * ny * nz);
    EXPECT_NEAR(mp.massKg, m, 1e-12 * m);
    // Voxel centres run from 0 to (n-1) h.
    EXPECT_NEAR(mp.centreOfMassLocalM.x(), (nx - 1) * h / 2, 1e-12);
    EXPECT_NEAR(mp.centreOfMassLocalM.z(), (nz - 1) * h / 2, 1e-12);
    // Solid cuboid: I_xx = m (b^2 + c^2) / 12.
    EXPECT_NEAR(mp.inertiaKgM2(0, 0), m * (b * b + c * c) / 12.0, 1e-12 * m);
    EXPECT_NEAR(mp.inertiaKgM2(1, 1), m * (a * a + c * c) / 12.0, 1e-12 * m);
    EXPECT_NEAR(mp.inertiaKgM2(2, 2), m * (a * a + b * b) / 12.0, 1e-12 * m);
    EXPECT_NEAR(mp.inertiaKgM2(0, 1), 0.0, 1e-12 * m);
}

TEST(MassProperties, LShapeMatchesHandComputation)
{
    // Three unit cubes (h = 1, rho = 1) at (0,0,0), (1,0,0), (0,1,0).
    // Centre (1/3, 1/3, 0). Point-mass sums about it: sum dx^2 = 2/3, dy^2 = 2/3, dx dy = -1/3.
    // I_xx = sum(dy^2 + dz^2) + 3/6 = 2/3 + 1/2; I_zz = 4/3 + 1/2; I_xy = -sum dx dy = +1/3.
    const MassProperties mp = computeMassProperties(*test::gridFromVoxels({Coord(0, 0, 0), Coord(1, 0, 0), Coord(0, 1, 0)}), 1.0, 1.0);
    EXPECT_DOUBLE_EQ(mp.massKg, 3.0);
    EXPECT_NEAR(mp.centreOfMassLocalM.x(), 1.0 / 3.0, 1e-15);
    EXPECT_NEAR(mp.centreOfMassLocalM.y(), 1.0 / 3.0, 1e-15);
    EXPECT_NEAR(mp.inertiaKgM2(0, 0), 2.0 / 3.0 + 0.5, 1e-14);
    EXPECT_NEAR(mp.inertiaKgM2(1, 1), 2.0 / 3.0 + 0.5, 1e-14);
    EXPECT_NEAR(mp.inertiaKgM2(2, 2), 4.0 / 3.0 + 0.5, 1e-14);
    EXPECT_NEAR(mp.inertiaKgM2(0, 1), 1.0 / 3.0, 1e-14);
    EXPECT_NEAR(mp.inertiaKgM2(0, 2), 0.0, 1e-14);
}

TEST(MassProperties, EmptyGridHasNoMass)
{
    const MassProperties mp = computeMassProperties(*test::gridFromVoxels({}), 1.0, 1.0);
    EXPECT_EQ(mp.voxelCount, 0);
    EXPECT_EQ(mp.massKg, 0.0);
}

TEST(Links, CountAndBreakKeepSymmetry)
{
    auto g = test::boxGrid(3, 3, 3);
    // A 3x3x3 block has 3 * (2*3*3) = 54 links.
    EXPECT_EQ(countLinks(*g), 54);
    EXPECT_TRUE(linksAreSymmetric(*g));
    auto acc = g->getAccessor();
    EXPECT_TRUE(breakLink(acc, Coord(1, 1, 1), kPosX));
    EXPECT_FALSE(breakLink(acc, Coord(2, 1, 1), kNegX)) << "the other side broke with it";
    EXPECT_EQ(countLinks(*g), 53);
    EXPECT_TRUE(linksAreSymmetric(*g));
    EXPECT_FALSE(breakLink(acc, Coord(2, 2, 2), kPosX)) << "no neighbour, no link";
}

TEST(Links, SingleVoxelHasSixExposedFacesAndNoLinks)
{
    auto g = test::gridFromVoxels({Coord(5, -3, 2)});
    EXPECT_EQ(countLinks(*g), 0);
    EXPECT_EQ(collectExposedFaces(*g).size(), 6u);
    EXPECT_EQ(boundaryVoxelsOf(collectExposedFaces(*g)).size(), 1u);
}

TEST(Links, ExposedFacesOfBlockAreItsSurface)
{
    auto g = test::boxGrid(4, 5, 6);
    EXPECT_EQ(collectExposedFaces(*g).size(), size_t(2 * (4 * 5 + 5 * 6 + 4 * 6)));
    // Interior 2x3x4 voxels are not on the boundary.
    EXPECT_EQ(boundaryVoxelsOf(collectExposedFaces(*g)).size(), size_t(4 * 5 * 6 - 2 * 3 * 4));
}

TEST(Components, FullyLinkedBlockIsOneComponent)
{
    auto g = test::boxGrid(20, 17, 9);
    const ComponentLabels labels = labelComponents(*g);
    EXPECT_EQ(labels.componentCount, 1u);
}

TEST(Components, OneLinkHoldsTwoHalvesTogether)
{
    // Two 8x8x8 blocks side by side along x; all links across the cut broken but one.
    auto g = test::boxGrid(16, 8, 8);
    auto acc = g->getAccessor();
    for (int y = 0; y < 8; ++y)
        for (int z = 0; z < 8; ++z)
            if (!(y == 3 && z == 4)) breakLink(acc, Coord(7, y, z), kPosX);
    EXPECT_EQ(labelComponents(*g).componentCount, 1u);
    breakLink(acc, Coord(7, 3, 4), kPosX);
    const ComponentLabels labels = labelComponents(*g);
    ASSERT_EQ(labels.componentCount, 2u);
    const auto parts = splitByLabels(*g, labels);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(parts[0]->activeVoxelCount(), 512u);
    EXPECT_EQ(parts[1]->activeVoxelCount(), 512u);
    EXPECT_TRUE(linksAreSymmetric(*parts[0]));
    EXPECT_EQ(countLinks(*parts[0]) + countLinks(*parts[1]), countLinks(*g));
}

TEST(Components, SplitPartsKeepTheIndexSpaceAndMass)
{
    auto g = test::boxGrid(10, 10, 10, 0.1);
    auto acc = g->getAccessor();
    for (int x = 0; x < 10; ++x)
        for (int y = 0; y < 10; ++y) breakLink(acc, Coord(x, y, 4), kPosZ);  // a horizontal cut
    const auto parts = splitByLabels(*g, labelComponents(*g));
    ASSERT_EQ(parts.size(), 2u);
    // Each part is its slab, in the parent's index space: z 0..4 and z 5..9, 500 voxels each, with
    // the mass and centre of a 1 x 1 x 0.5 m slab of unit density (centres at index 2 and 7).
    std::vector<std::pair<openvdb::CoordBBox, MassProperties>> found;
    for (const auto& part : parts) found.push_back({part->evalActiveVoxelBoundingBox(), computeMassProperties(*part, 0.1, 1.0)});
    std::sort(found.begin(), found.end(), [](const auto& x, const auto& y) { return x.first.min().z() < y.first.min().z(); });
    for (int k = 0; k < 2; ++k) {
        EXPECT_EQ(found[k].first, openvdb::CoordBBox(Coord(0, 0, 5 * k), Coord(9, 9, 5 * k + 4))) << k;
        EXPECT_EQ(found[k].second.voxelCount, 500) << k;
        EXPECT_NEAR(found[k].second.massKg, 0.5, 1e-12) << k;
        EXPECT_LT((found[k].second.centreOfMassLocalM - Eigen::Vector3d(0.45, 0.45, 0.2 + 0.5 * k)).norm(), 1e-12) << k;
    }
}

TEST(Components, CheckerboardCutsGiveManyPiecesIdenticallyForAnyThreadCount)
{
    // Cut a 40^3 block into 5^3-voxel cubes: 8^3 = 512 pieces.
    auto g = test::boxGrid(40, 40, 40);
    auto acc = g->getAccessor();
    for (int x = 0; x < 40; ++x)
        for (int y = 0; y < 40; ++y)
            for (int z = 0; z < 40; ++z) {
                if (x % 5 == 4) breakLink(acc, Coord(x, y, z), kPosX);
                if (y % 5 == 4) breakLink(acc, Coord(x, y, z), kPosY);
                if (z % 5 == 4) breakLink(acc, Coord(x, y, z), kPosZ);
            }
    ComponentLabels one, two;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = labelComponents(*g);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
        two = labelComponents(*g);
    }
    EXPECT_EQ(one.componentCount, 512u);
    EXPECT_EQ(one.labelOfSlot, two.labelOfSlot);
    for (const auto& part : splitByLabels(*g, one)) EXPECT_EQ(part->activeVoxelCount(), 125u);
}

TEST(Body, IndexToWorldMatchesPose)
{
    Body b = makeBody(test::boxGrid(3, 2, 5, 0.2), 0.2, 1000.0);
    b.motion.positionM = Eigen::Vector3d(1.0, -2.0, 3.0);
    b.motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
    const auto xf = b.indexToWorld();
    for (const Coord c : {Coord(0, 0, 0), Coord(2, 1, 4), Coord(1, 0, 3)}) {
        const openvdb::Vec3d w = xf->indexToWorld(c);
        const Eigen::Vector3d expected = b.voxelWorldM(c);
        EXPECT_NEAR((Eigen::Vector3d(w.x(), w.y(), w.z()) - expected).norm(), 0.0, 1e-12);
    }
}
