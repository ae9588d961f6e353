#include <spall/dynamics/DebrisScenes.h>

#include <cmath>
#include <random>

namespace spall {

namespace {

/// A cube of edge^3 voxels with every link intact; its centre of mass at the origin.
Body cubeFragment(int edge, double h)
{
    LinkGrid::Ptr grid = LinkGrid::create(0);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(edge - 1)), 0, true);
    linkAllNeighbours(*grid);
    return makeBody(grid, h, 2000.0);
}

/// Fragments along each side of the lattice: side^2 columns, as many layers as needed.
int latticeSide(int fragments) { return std::max(1, static_cast<int>(std::ceil(std::cbrt(static_cast<double>(fragments))))); }

}  // namespace

DebrisScene makeDebrisPile(int fragments, int edge, double h, uint64_t seed)
{
    DebrisScene scene;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> turn(-0.15, 0.15);
    const Body prototype = cubeFragment(edge, h);
    const int side = latticeSide(fragments);
    const double size = edge * h;
    // Turned cubes need up to size * (cos + sin) of room; 1.2 leaves a gap for the stagger.
    const double pitch = 1.2 * size;
    for (int n = 0; n < fragments; ++n) {
        const int layer = n / (side * side), column = (n / side) % side, row = n % side;
        const double stagger = (layer % 2) * 0.25 * size;
        Body body = prototype;
        body.id = n;
        body.motion.positionM = Eigen::Vector3d((column + 0.5) * pitch + stagger, (row + 0.5) * pitch + stagger, (layer + 0.51) * 1.01 * size);
        body.motion.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(turn(rng), Eigen::Vector3d::UnitZ()));
        scene.boundaryVoxels += static_cast<int64_t>(body.boundaryVoxels.size());
        scene.bodies.push_back(std::move(body));
    }
    // Four walls around the pile, as tall as it.
    const double width = side * pitch + 0.25 * size, height = (fragments / (side * side) + 2) * size;
    const double thickness = size;
    for (int axis = 0; axis < 2; ++axis)
        for (int sign : {-1, 1}) {
            StaticBox wall;
            wall.halfExtentM = Eigen::Vector3d(0.5 * width + thickness, 0.5 * width + thickness, 0.5 * height);
            wall.halfExtentM[axis] = 0.5 * thickness;
            wall.centreM = Eigen::Vector3d(0.5 * width, 0.5 * width, 0.5 * height);
            wall.centreM[axis] = 0.5 * width + sign * (0.5 * width + 0.5 * thickness);
            scene.world.colliders.push_back(wall);
        }
    return scene;
}

DebrisScene makeExplosionCloud(int fragments, int edge, double h, double speedMS, uint64_t seed)
{
    DebrisScene scene;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const Body prototype = cubeFragment(edge, h);
    const int side = latticeSide(fragments);
    const double pitch = 1.05 * edge * h;
    const Eigen::Vector3d centre = Eigen::Vector3d::Constant(0.5 * side * pitch) + Eigen::Vector3d(0, 0, 2.0 * side * pitch);
    for (int n = 0; n < fragments; ++n) {
        const int layer = n / (side * side), column = (n / side) % side, row = n % side;
        Body body = prototype;
        body.id = n;
        body.motion.positionM = Eigen::Vector3d((column + 0.5) * pitch, (row + 0.5) * pitch, (layer + 0.5) * pitch + 2.0 * side * pitch);
        const Eigen::Vector3d out = body.motion.positionM - centre;
        const double radius = 0.5 * std::sqrt(3.0) * side * pitch;
        body.motion.linearVelocityMS = speedMS * out / radius + 0.1 * speedMS * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
        // Spin that moves corners at up to a quarter of the flight speed.
        body.motion.angularVelocityRadS = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * (0.25 * speedMS / (edge * h));
        scene.boundaryVoxels += static_cast<int64_t>(body.boundaryVoxels.size());
        scene.bodies.push_back(std::move(body));
    }
    return scene;
}

}  // namespace spall
