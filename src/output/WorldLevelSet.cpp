// The frame's `debris` grid (FrameWriter.h): every piece's level set in one world-aligned grid.
#include <spall/output/FrameWriter.h>

#include <algorithm>
#include <cmath>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/SignedFloodFill.h>

namespace spall {

openvdb::FloatGrid::Ptr levelSetInWorld(const openvdb::FloatGrid& piece, double sampleM, float halfWidthSamples)
{
    auto world = openvdb::createLevelSet<openvdb::FloatGrid>(sampleM, halfWidthSamples);
    const float band = world->background();
    // A piece moves rigidly and its samples are as far apart as the world's, so the world's
    // samples near each of its band's samples are the world's band, and a rigid motion keeps a
    // signed distance one: trilinear interpolation of the piece at them is the distance there.
    const openvdb::FloatGrid::ConstAccessor in = piece.getConstAccessor();
    const openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sample(in, piece.transform());
    auto out = world->getAccessor();
    for (auto it = piece.cbeginValueOn(); it; ++it) {
        if (std::abs(*it) >= band) continue;
        const openvdb::Vec3d index = world->worldToIndex(piece.indexToWorld(it.getCoord()));
        const openvdb::Coord corner = openvdb::Coord::floor(index);
        for (int c = 0; c < 8; ++c) {
            const openvdb::Coord q = corner.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1);
            if (out.isValueOn(q)) continue;
            const float distance = sample.wsSample(world->indexToWorld(q));
            if (std::abs(distance) < band) out.setValueOn(q, distance);
        }
    }
    // The samples off the band take the sign of the side they lie on (inside: −band).
    openvdb::tools::signedFloodFill(world->tree());
    return world;
}

openvdb::FloatGrid::Ptr levelSetUnion(const std::vector<openvdb::FloatGrid::ConstPtr>& pieces, double sampleM, float halfWidthSamples)
{
    auto world = openvdb::createLevelSet<openvdb::FloatGrid>(sampleM, halfWidthSamples);
    // The union is the least distance: each band sample keeps the least of the pieces' there,
    // whatever the order they come in (pieces touch but do not overlap, so their bands are the
    // union's band).
    auto out = world->getAccessor();
    for (const openvdb::FloatGrid::ConstPtr& piece : pieces)
        for (auto it = piece->cbeginValueOn(); it; ++it) {
            float earlier = 0.0f;
            out.setValueOn(it.getCoord(), out.probeValue(it.getCoord(), earlier) ? std::min(earlier, *it) : *it);
        }
    openvdb::tools::signedFloodFill(world->tree());
    return world;
}

}  // namespace spall
