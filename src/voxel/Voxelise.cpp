#include <spall/voxel/Voxelise.h>

#include "MeshHeader.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace spall {

namespace {

void checkVoxelSize(double h)
{
    if (!(h > 0.0) || !std::isfinite(h)) {
        std::ostringstream msg;
        msg << "voxel size must be a positive finite number of metres, got " << h;
        throw InputError(msg.str());
    }
}

void checkVoxelBudget(const Eigen::Vector3d& extentM, double h, int64_t maxVoxels, const std::string& what)
{
    const double estimate = std::ceil(extentM.x() / h + 1) * std::ceil(extentM.y() / h + 1) * std::ceil(extentM.z() / h + 1);
    if (estimate > static_cast<double>(maxVoxels)) {
        std::ostringstream msg;
        msg << what << ": at voxel size " << h << " m the bounding box holds about " << static_cast<double>(estimate)
            << " voxels, above the limit of " << maxVoxels << " (raise --max-voxels or use a larger voxel size)";
        throw InputError(msg.str());
    }
}

/// Number of edges not shared by exactly two triangles (after welding equal positions).
int64_t countOpenEdges(const TriangleMesh& mesh)
{
    std::map<std::pair<int, int>, int> uses;
    for (const auto& t : mesh.triangles) {
        for (int e = 0; e < 3; ++e) {
            int a = t[e], b = t[(e + 1) % 3];
            if (a > b) std::swap(a, b);
            ++uses[{a, b}];
        }
    }
    int64_t open = 0;
    for (const auto& [edge, count] : uses) open += (count != 2);
    return open;
}

LinkGrid::Ptr newLinkGrid(double h)
{
    LinkGrid::Ptr grid = LinkGrid::create(0);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    grid->setName("solid");
    return grid;
}

}  // namespace

TriangleMesh loadMesh(const std::string& path, std::vector<std::string>* notes)
{
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw InputError(path + ": no such file");
    if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory, not a mesh file");
    {
        std::ifstream probe(path, std::ios::binary);
        if (!probe) throw InputError(path + ": cannot be read (permission denied?)");
        if (probe.peek() == std::ifstream::traits_type::eof()) throw InputError(path + ": file is empty");
    }
    checkDeclaredCounts(path);
    Assimp::Importer importer;
    // Points and lines are dropped (they enclose nothing); identical vertices are welded so that
    // open edges can be counted.
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                       aiProcess_SortByPType | aiProcess_PreTransformVertices);
    if (!scene) throw InputError(path + ": cannot be read as a mesh: " + importer.GetErrorString());

    TriangleMesh mesh;
    int64_t skipped = 0;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh* am = scene->mMeshes[m];
        const int base = static_cast<int>(mesh.positionsM.size());
        for (unsigned v = 0; v < am->mNumVertices; ++v) {
            const aiVector3D& p = am->mVertices[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw InputError(path + ": vertex " + std::to_string(v) + " of mesh " + std::to_string(m) + " is not finite");
            mesh.positionsM.emplace_back(p.x, p.y, p.z);
        }
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const aiFace& face = am->mFaces[f];
            if (face.mNumIndices != 3) {
                ++skipped;
                continue;
            }
            mesh.triangles.emplace_back(base + int(face.mIndices[0]), base + int(face.mIndices[1]), base + int(face.mIndices[2]));
        }
    }
    if (mesh.triangles.empty()) throw InputError(path + ": the file holds no triangles (no faces to enclose a volume)");
    if (notes && skipped > 0) notes->push_back(std::to_string(skipped) + " point or line primitives ignored");
    if (notes && scene->mNumMeshes > 1) notes->push_back(std::to_string(scene->mNumMeshes) + " meshes merged into one solid");
    return mesh;
}

double meshVolumeM3(const TriangleMesh& mesh)
{
    double sixV = 0.0;
    for (const auto& t : mesh.triangles) {
        const Eigen::Vector3d a = mesh.positionsM[t[0]].cast<double>();
        const Eigen::Vector3d b = mesh.positionsM[t[1]].cast<double>();
        const Eigen::Vector3d c = mesh.positionsM[t[2]].cast<double>();
        sixV += a.dot(b.cross(c));
    }
    return std::abs(sixV) / 6.0;
}

namespace {

/// OpenVDB builds an unsigned distance band and flood-fills the sign, so winding order and
/// self-intersections do not matter; a narrow band of 3 voxels closes small holes.
openvdb::FloatGrid::Ptr signedDistanceOf(const TriangleMesh& mesh, double h, const std::string& sourceName, Interrupter* interrupter)
{
    std::vector<openvdb::Vec3s> points;
    points.reserve(mesh.positionsM.size());
    for (const auto& p : mesh.positionsM) points.emplace_back(p.x(), p.y(), p.z());
    std::vector<openvdb::Vec3I> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    auto transform = openvdb::math::Transform::createLinearTransform(h);
    if (!interrupter) return openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
    struct VdbInterrupter {
        Interrupter* inner;
        void start(const char* = nullptr) {}
        void end() {}
        bool wasInterrupted(int percent = -1) { return inner->wasInterrupted(percent); }
    } adaptor{interrupter};
    auto sdf = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(adaptor, *transform, points, triangles, 3.0f);
    // OpenVDB returns what it has when interrupted: that is no result.
    if (interrupter->wasInterrupted()) throw VoxeliseInterrupted(sourceName + ": voxelising was interrupted");
    return sdf;
}

}  // namespace

VoxeliseResult voxeliseMesh(const TriangleMesh& mesh, const VoxeliseSettings& settings, const std::string& sourceName,
                            Interrupter* interrupter)
{
    checkVoxelSize(settings.voxelSizeM);
    const double h = settings.voxelSizeM;
    VoxeliseResult result;
    if (mesh.triangles.empty()) throw InputError(sourceName + ": mesh has no faces");

    Eigen::Vector3f lo = mesh.positionsM[0], hi = lo;
    for (const auto& p : mesh.positionsM) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    checkVoxelBudget((hi - lo).cast<double>(), h, settings.maxVoxels, sourceName);

    const int64_t openEdges = countOpenEdges(mesh);
    if (openEdges > 0) {
        result.notes.push_back(std::to_string(openEdges) +
                               " open edges (the mesh is not watertight): the interior comes from OpenVDB's sign "
                               "flood fill and holes narrower than about 3 voxels are closed");
    }

    const openvdb::FloatGrid::Ptr sdf = signedDistanceOf(mesh, h, sourceName, interrupter);
    auto interior = openvdb::tools::sdfInteriorMask(*sdf);

    result.grid = newLinkGrid(h);
    interior->tree().voxelizeActiveTiles();
    copyActiveTopology(result.grid->tree(), interior->tree(), 0);
    result.voxelCount = static_cast<int64_t>(result.grid->activeVoxelCount());
    if (result.voxelCount == 0) {
        throw InputError(sourceName + ": the mesh encloses no voxel centre at voxel size " + std::to_string(h) +
                         " m (it is open, flat, or thinner than a voxel)");
    }
    if (result.voxelCount > settings.maxVoxels) {
        throw InputError(sourceName + ": " + std::to_string(result.voxelCount) + " voxels, above the limit of " +
                         std::to_string(settings.maxVoxels));
    }
    linkAllNeighbours(*result.grid);
    return result;
}

VoxeliseResult voxelisePrimitive(const Primitive& primitive, const VoxeliseSettings& settings)
{
    checkVoxelSize(settings.voxelSizeM);
    const double h = settings.voxelSizeM;
    const Eigen::Vector3d& s = primitive.sizeM;
    if (!(s.minCoeff() > 0.0) || !s.allFinite()) throw InputError("primitive size must be positive and finite (unit: m)");
    Eigen::Vector3d half = Eigen::Vector3d::Zero();
    switch (primitive.shape) {
    case PrimitiveShape::Box: half = 0.5 * s; break;
    case PrimitiveShape::Sphere: half = Eigen::Vector3d::Constant(s.x()); break;
    case PrimitiveShape::Cylinder: half = Eigen::Vector3d(s.x(), s.x(), 0.5 * s.z()); break;
    }
    checkVoxelBudget(2.0 * half, h, settings.maxVoxels, "primitive");

    // A box is rounded to whole voxels per axis and centred: an odd count puts a voxel centre on
    // the axis (offset 0), an even count puts a face there (offset h/2), so the voxel cubes tile the
    // box exactly. Spheres and cylinders keep the voxels whose centre is inside.
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    openvdb::Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
        const int n = std::max(1, static_cast<int>(std::lround(2.0 * half[a] / h)));
        offset[a] = (n % 2 == 0) ? 0.5 * h : 0.0;
        lo[a] = -(n / 2);
        hi[a] = lo[a] + n - 1;
    }
    VoxeliseResult result;
    result.localOffsetM = offset;
    result.grid = newLinkGrid(h);
    if (primitive.shape == PrimitiveShape::Box) {
        result.grid->tree().denseFill(openvdb::CoordBBox(lo, hi), 0, true);
    } else {
        auto acc = result.grid->getAccessor();
        const double r2 = s.x() * s.x();
        for (int i = lo.x(); i <= hi.x(); ++i)
            for (int j = lo.y(); j <= hi.y(); ++j)
                for (int k = lo.z(); k <= hi.z(); ++k) {
                    const double x = i * h + offset.x(), y = j * h + offset.y(), z = k * h + offset.z();
                    const bool inside = primitive.shape == PrimitiveShape::Sphere ? x * x + y * y + z * z < r2
                                                                                  : x * x + y * y < r2 && std::abs(z) < half.z();
                    if (inside) acc.setValueOn(openvdb::Coord(i, j, k), 0);
                }
    }
    result.voxelCount = static_cast<int64_t>(result.grid->activeVoxelCount());
    if (result.voxelCount == 0) throw InputError("primitive is smaller than one voxel");
    linkAllNeighbours(*result.grid);
    return result;
}

}  // namespace spall
