// Masonry in the deformable phase with particles taller than a course (issue 47, item 7): its
// units unresolved, it breaks as homogenised masonry, a crack across the courses as strong as
// the resolved lattice's, one along the bed joints the joints'.
#include "BarLoading.h"
#include "LatticeTestUtil.h"

#include <spall/fracture/Material.h>
#include <spall/lattice/Lattice.h>

#include <gtest/gtest.h>

#include <cstdio>

using namespace spall;
using namespace spall::test;

namespace {

/// The preset's masonry (no scatter) in a square bar along its courses (x), side `sideM`,
/// pulled apart slowly at particle size h: a crack across the courses.
BarPull pullAlongTheCourses(double h, double sideM)
{
    BarSpec spec;
    spec.material = withoutStrengthScatter(findMaterialPreset("brick-masonry"));
    spec.h = h;
    spec.lengthM = 0.9;  // four bricks
    spec.sideM = sideM;
    spec.notch = 1.0;  // the joints and units choose where it cracks
    // 12 ms at 0.05 m/s stretches the bar 0.6 mm, three times its strain at 0.7 MPa.
    return loadBar(spec, 0.012, 0.5 * spec.material.tensileStrengthPa);
}

}  // namespace

TEST(Lattice, MasonryCoarserThanACourseCracksAcrossItsCoursesAsItsResolvedLatticeDoes)
{
    const Material masonry = findMaterialPreset("brick-masonry");
    // The reference: the units and joints resolved (2.5 cm, the default scene's voxels), a bar
    // eight courses tall, so the cracks step through head joints and slide along bed joints.
    const BarPull resolved = pullAlongTheCourses(0.025, 0.6);
    // Particles of 9 cm, taller than a 7.5 cm course: a bar four particles on a side.
    const BarPull coarse = pullAlongTheCourses(0.09, 0.36);
    std::printf("across the courses: resolved %.3f MPa (%.1f J/m^2), homogenised %.3f MPa (%.1f J/m^2); the joints' ft %.2f MPa\n",
                resolved.peakStressPa / 1e6, resolved.dissipatedJ / (0.6 * 0.6), coarse.peakStressPa / 1e6, coarse.dissipatedJ / (0.36 * 0.36),
                masonry.tensileStrengthPa / 1e6);
    ASSERT_TRUE(resolved.fellPastPeak && coarse.fellPastPeak);
    // Joints alone (what coarse masonry was) would be 45 % weaker than the resolved lattice.
    EXPECT_GT(resolved.peakStressPa, 1.5 * masonry.tensileStrengthPa);
    EXPECT_NEAR(coarse.peakStressPa / resolved.peakStressPa, 1.0, 0.25);
    // EN 1996-1-1 (3.6.3, recommended values for clay units) puts the flexural strength with the
    // failure plane perpendicular to the bed joints at 2 (mortar weaker than M5) to 4 times that
    // with the plane parallel to them.
    EXPECT_GE(acrossCoursesStrengthRatio(masonry), 2.0);
    EXPECT_LE(acrossCoursesStrengthRatio(masonry), 4.0);
}
