#include <spall/voxel/Voxelise.h>

#include "MeshHeader.h"
#include "MeshOrientation.h"
#include "WindingNumber.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
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

/// How far past a half-multiple of h a mesh is shifted so that no face lies on a voxel centre
/// (unit: voxels): far above float rounding at any coordinate a scene holds, far below a voxel.
constexpr double kTieBreakVoxels = 0.01;

double boxVoxels(const Eigen::Vector3d& extentM, double h)
{
    return std::ceil(extentM.x() / h + 1) * std::ceil(extentM.y() / h + 1) * std::ceil(extentM.z() / h + 1);
}

void checkVoxelBudget(double estimate, double h, int64_t maxVoxels, const std::string& what)
{
    if (estimate > static_cast<double>(maxVoxels)) {
        std::ostringstream msg;
        msg << what << ": at voxel size " << h << " m the bounding box holds about " << estimate << " voxels, above the limit of "
            << maxVoxels << " (max_voxels in a scene, --max-voxels for spall voxelise; or use a larger voxel size)";
        throw InputError(msg.str());
    }
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
    // Validation refuses indices out of range and empty faces. spall splits polygons itself:
    // assimp's triangulation aborts the process on a mesh flagged as holding polygons that holds
    // none (found by fuzz_mesh on a malformed PLY).
    const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_PreTransformVertices);
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
            if (face.mNumIndices < 3) {  // a point or a line encloses nothing
                ++skipped;
                continue;
            }
            // A fan from the first corner: exact for convex polygons, and for any planar polygon
            // its triangles' solid angles add up to the polygon's, which is all the winding number needs.
            for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
                mesh.triangles.emplace_back(base + int(face.mIndices[0]), base + int(face.mIndices[k]), base + int(face.mIndices[k + 1]));
        }
    }
    if (mesh.triangles.empty()) throw InputError(path + ": the file holds no triangles (no faces to enclose a volume)");
    if (notes && skipped > 0) notes->push_back(std::to_string(skipped) + " point or line primitives ignored");
    if (notes && scene->mNumMeshes > 1) notes->push_back(std::to_string(scene->mNumMeshes) + " meshes merged into one solid");
    return mesh;
}

namespace {

/// spall's interrupter as OpenVDB asks for one.
struct VdbInterrupter {
    Interrupter* inner;
    void start(const char* = nullptr) {}
    void end() {}
    bool wasInterrupted(int percent = -1) { return inner && inner->wasInterrupted(percent); }
};

/// The mesh as OpenVDB's mesh converters take it.
struct VdbMesh {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;

    explicit VdbMesh(const TriangleMesh& mesh)
    {
        points.reserve(mesh.positionsM.size());
        for (const auto& p : mesh.positionsM) points.emplace_back(p.x(), p.y(), p.z());
        triangles.reserve(mesh.triangles.size());
        for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    }
};

/// OpenVDB builds an unsigned distance band and flood-fills the sign: exact for watertight meshes
/// whatever their winding; a hole wider than the 3-voxel band lets the outside flood in.
void fillLevelSetInterior(const TriangleMesh& mesh, LinkGrid& solid, const std::string& sourceName, Interrupter* interrupter)
{
    const VdbMesh vdb(mesh);
    VdbInterrupter adaptor{interrupter};
    const auto sdf = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(adaptor, solid.transform(), vdb.points, vdb.triangles, 3.0f);
    // OpenVDB returns what it has when interrupted: that is no result.
    if (adaptor.wasInterrupted()) throw VoxeliseInterrupted(sourceName + ": voxelising was interrupted");
    auto interior = openvdb::tools::sdfInteriorMask(*sdf);
    interior->tree().voxelizeActiveTiles();
    copyActiveTopology(solid.tree(), interior->tree(), 0);
}

/// Voxels whose centres lie within half the thickness of the surface: OpenVDB's unsigned distance
/// (in metres) over a band just wide enough.
void fillShell(const TriangleMesh& mesh, double thicknessM, LinkGrid& solid, const std::string& sourceName, Interrupter* interrupter)
{
    const double h = solid.voxelSize()[0];
    if (thicknessM < h) {
        std::ostringstream msg;
        msg << sourceName << ": a shell " << thicknessM << " m thick is thinner than a voxel (" << h << " m): it would not hold together";
        throw InputError(msg.str());
    }
    const VdbMesh vdb(mesh);
    VdbInterrupter adaptor{interrupter};
    const float halfWidthVoxels = static_cast<float>(0.5 * thicknessM / h) + 1.0f;
    const auto distance = openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(
        adaptor, solid.transform(), vdb.points, vdb.triangles, std::vector<openvdb::Vec4I>(), halfWidthVoxels);
    if (adaptor.wasInterrupted()) throw VoxeliseInterrupted(sourceName + ": voxelising was interrupted");
    auto accessor = solid.getAccessor();
    for (auto it = distance->cbeginValueOn(); it; ++it)
        if (*it <= 0.5 * thicknessM) accessor.setValueOn(it.getCoord(), 0);
}

std::string cubicMetres(double v)
{
    std::ostringstream out;
    out << std::setprecision(3) << v << " m^3";
    return out.str();
}

/// A fill that lost most of what the mesh encloses is an error, not a success; a smaller gap is a note.
void checkFilledVolume(VoxeliseResult& result, double h, const std::string& sourceName)
{
    const double filled = static_cast<double>(result.voxelCount) * h * h * h;
    const double enclosed = result.enclosedVolumeM3;
    if (enclosed < 8.0 * h * h * h) return;  // a few voxels: discretisation decides, not the fill
    if (filled < 0.5 * enclosed) {
        throw InputError(sourceName + ": the voxels hold " + cubicMetres(filled) + " of the " + cubicMetres(enclosed) +
                         " the mesh encloses: the fill lost most of the volume (is the mesh a surface with a large "
                         "hole, or thinner than a voxel?)");
    }
    if (std::abs(filled - enclosed) > 0.05 * enclosed)
        result.notes.push_back("the voxels hold " + cubicMetres(filled) + ", the mesh encloses " + cubicMetres(enclosed) +
                               " (counted from the surface, closing holes by a cone from each shell's middle)");
}

void noteRepairs(VoxeliseResult& result, const MeshTopology& topology, InsideTest test)
{
    if (topology.turnedTriangles > 0)
        result.notes.push_back(std::to_string(topology.turnedTriangles) + " triangles were wound against their neighbours and were turned");
    if (topology.openEdges > 0)
        result.notes.push_back(std::to_string(topology.openEdges) + " open edges (the mesh is not watertight): the inside comes from " +
                               (test == InsideTest::WindingNumber ? "the generalised winding number, which bridges holes"
                                                                  : "OpenVDB's sign flood fill, which closes only holes narrower than about 3 voxels"));
    if (topology.hollows > 0 && test == InsideTest::LevelSet)
        result.notes.push_back(std::to_string(topology.hollows) + " sealed hollows are filled: OpenVDB's level set takes everything "
                               "the flood fill from outside cannot reach as inside; the winding number (inside: winding-number) keeps them");
}

}  // namespace

double boundingBoxVoxels(const TriangleMesh& mesh, double h)
{
    Eigen::AlignedBox3f bounds;
    for (const auto& p : mesh.positionsM) bounds.extend(p);
    return mesh.positionsM.empty() ? 0.0 : boxVoxels(bounds.sizes().cast<double>(), h);
}

Eigen::Vector3d primitiveHalfExtentM(const Primitive& primitive)
{
    const Eigen::Vector3d& s = primitive.sizeM;
    switch (primitive.shape) {
    case PrimitiveShape::Box: return 0.5 * s;
    case PrimitiveShape::Sphere: return Eigen::Vector3d::Constant(s.x());
    case PrimitiveShape::Cylinder: return Eigen::Vector3d(s.x(), s.x(), 0.5 * s.z());
    }
    return 0.5 * s;
}

double boundingBoxVoxels(const Primitive& primitive, double h) { return boxVoxels(2.0 * primitiveHalfExtentM(primitive), h); }

VoxeliseResult voxeliseMesh(const TriangleMesh& mesh, const VoxeliseSettings& settings, const std::string& sourceName,
                            Interrupter* interrupter)
{
    checkVoxelSize(settings.voxelSizeM);
    const double h = settings.voxelSizeM;
    if (mesh.triangles.empty()) throw InputError(sourceName + ": mesh has no faces");
    checkVoxelBudget(boundingBoxVoxels(mesh, h), h, settings.maxVoxels, sourceName);

    // Voxel cubes tile the object's frame from its origin, centres at (i + 1/2) h: faces modelled
    // at round coordinates (CAD's habit) then lie between centres, where the level set and the
    // winding number agree, and the cubes end on them. A hundredth of a voxel more breaks ties
    // for faces at half-multiples of h (coordinates h does not divide) half-open, the same way
    // by either test. The grid indexes the shifted mesh; localOffsetM shifts it back.
    const float shiftM = static_cast<float>(kTieBreakVoxels * h - 0.5 * h);
    TriangleMesh outward = mesh;
    for (Eigen::Vector3f& x : outward.positionsM) x.array() += shiftM;
    const MeshTopology topology = orientOutward(outward);
    InsideTest test = settings.insideTest;
    // OpenVDB's level set finds its sign by flood fill from outside, which fills sealed hollows;
    // the winding number of the shells, hollows wound inward, leaves them empty.
    if (test == InsideTest::Auto)
        test = topology.openEdges == 0 && topology.hollows == 0 ? InsideTest::LevelSet : InsideTest::WindingNumber;
    VoxeliseResult result;
    result.localOffsetM = Eigen::Vector3d::Constant(-double(shiftM));
    result.enclosedVolumeM3 = topology.enclosedVolumeM3;
    if (settings.shellThicknessM == 0.0) noteRepairs(result, topology, test);
    result.grid = newLinkGrid(h);
    if (settings.shellThicknessM > 0.0)
        fillShell(outward, settings.shellThicknessM, *result.grid, sourceName, interrupter);
    else if (test == InsideTest::LevelSet)
        fillLevelSetInterior(outward, *result.grid, sourceName, interrupter);
    else
        fillWindingNumberInterior(outward, *result.grid, sourceName, interrupter);
    result.voxelCount = static_cast<int64_t>(result.grid->activeVoxelCount());
    if (result.voxelCount == 0) {
        throw InputError(sourceName + ": the mesh encloses no voxel centre at voxel size " + std::to_string(h) + " m (" +
                         (topology.openEdges > 0 ? "it is an open surface, such as a plane or a terrain patch, that encloses nothing; "
                                                   "shell_thickness_m (--shell-thickness) makes a solid of it"
                                                 : "it is flat or thinner than a voxel") + ")");
    }
    if (result.voxelCount > settings.maxVoxels) {
        throw InputError(sourceName + ": " + std::to_string(result.voxelCount) + " voxels, above the limit of " +
                         std::to_string(settings.maxVoxels));
    }
    if (settings.shellThicknessM == 0.0) checkFilledVolume(result, h, sourceName);
    linkAllNeighbours(*result.grid);
    return result;
}

VoxeliseResult voxelisePrimitive(const Primitive& primitive, const VoxeliseSettings& settings)
{
    checkVoxelSize(settings.voxelSizeM);
    const double h = settings.voxelSizeM;
    const Eigen::Vector3d& s = primitive.sizeM;
    if (!(s.minCoeff() > 0.0) || !s.allFinite()) throw InputError("primitive size must be positive and finite (unit: m)");
    const Eigen::Vector3d half = primitiveHalfExtentM(primitive);
    checkVoxelBudget(boundingBoxVoxels(primitive, h), h, settings.maxVoxels, "primitive");

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
