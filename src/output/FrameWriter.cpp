#include <spall/output/FrameWriter.h>

#include <spall/output/FragmentSurface.h>
#include <spall/voxel/VdbIo.h>

#include <spall/core/Error.h>
#include <spall/core/Hash.h>
#include <spall/core/Parallel.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

namespace spall {

namespace {

/// Hash of a tree's active voxels and values, in the tree's own (canonical) order.
uint64_t contentHash(const openvdb::FloatTree& tree)
{
    uint64_t hash = 0;
    for (auto it = tree.cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        for (int32_t v : {c.x(), c.y(), c.z(), static_cast<int32_t>(*it)}) hash = splitmix64(hash ^ uint32_t(v));
    }
    return hash;
}

bool sameContent(const openvdb::FloatTree& a, const openvdb::FloatTree& b)
{
    if (!a.hasSameTopology(b)) return false;
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> other(b);
    for (auto it = a.cbeginValueOn(); it; ++it)
        if (other.getValue(it.getCoord()) != *it) return false;
    return true;
}

openvdb::Vec3d toVdb(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

FrameWriter::FrameWriter(std::string outputDirectory, const OutputSettings& settings, std::vector<Material> materials)
    : mDirectory(std::move(outputDirectory)), mSettings(settings), mMaterials(std::move(materials))
{
}

std::string FrameWriter::framePath(const std::string& directory, int frameNumber)
{
    char name[64];
    std::snprintf(name, sizeof name, "fragments.%04d.vdb", frameNumber);
    return (std::filesystem::path(directory) / name).string();
}

openvdb::FloatTree::Ptr FrameWriter::intern(std::unordered_multimap<uint64_t, Interned>& pool, const openvdb::FloatTree::Ptr& content,
                                            uint64_t hash, const std::function<openvdb::FloatTree::Ptr()>& derive)
{
    auto [first, last] = pool.equal_range(hash);
    for (auto it = first; it != last; ++it)
        if (sameContent(*it->second.content, *content)) return it->second.derived;
    return pool.emplace(hash, Interned{content, derive()})->second.derived;
}

namespace {

/// Whether the broken face of `voxel` runs along a joint of its masonry. Voxels taller than a
/// course do not resolve the units: then, as the lattice takes it (Lattice::classifyUnitBonds),
/// faces across z are the bed joints' and the others homogenised masonry's.
bool acrossJoint(const Material& material, const openvdb::Coord& voxel, int face, double voxelSizeM)
{
    if (!hasUnits(material)) return false;
    if (!unitsResolvedBy(material, voxelSizeM)) return faceAxis(face) == 2;
    const openvdb::Coord other = voxel + faceOffset(face);
    return spall::acrossJoint(material, Eigen::Vector3d(voxel.x(), voxel.y(), voxel.z()) * voxelSizeM,
                              Eigen::Vector3d(other.x(), other.y(), other.z()) * voxelSizeM);
}

}  // namespace

const Material* FrameWriter::materialOf(const Body& body) const
{
    return body.materialIndex >= 0 && size_t(body.materialIndex) < mMaterials.size() ? &mMaterials[body.materialIndex] : nullptr;
}

SurfaceStyle FrameWriter::surfaceStyle() const
{
    return {mSettings.levelSetSubdivisions, mSettings.fractureSmoothingSteps, mSettings.fractureRoughnessVoxels, kLevelSetHalfWidthSamples};
}

namespace {

/// A shape of fewer voxel leaves is made whole: one change's region holds as many.
constexpr openvdb::Index64 kLeastLeavesToUpdate = 64;

/// Whether every voxel of `bounds` lies at or above `origin` on each axis.
bool startsAtOrAbove(const openvdb::CoordBBox& bounds, const openvdb::Coord& origin)
{
    return bounds.min().x() >= origin.x() && bounds.min().y() >= origin.y() && bounds.min().z() >= origin.z();
}

}  // namespace

const FrameWriter::FragmentTrees* FrameWriter::earlierShapeOf(const Body& body) const
{
    if (body.grid->constTree().empty()) return nullptr;
    const openvdb::Coord first = body.grid->constTree().cbeginValueOn().getCoord();
    for (const auto& [id, trees] : mByBody) {
        if (!trees.shape.voxels) continue;
        const bool sibling = body.parentId != kNoBodyId && trees.parentId == body.parentId;
        if ((id == body.id || id == body.parentId || sibling) && startsAtOrAbove(body.indexBounds, trees.originIjk) &&
            trees.shape.voxels->isValueOn(first - trees.originIjk))
            return &trees;
    }
    return nullptr;
}

const FrameWriter::FragmentTrees& FrameWriter::treesOf(const Body& body)
{
    auto found = mByBody.find(body.id);
    if (found != mByBody.end() && found->second.madeFrom.lock() == body.grid) return mShownNow.insert_or_assign(body.id, found->second).first->second;
    const bool levelSet = mSettings.fragmentGrids == FragmentGrids::LevelSet;
    // A piece that cracked further, or broke from one shown before, takes that one's origin, so
    // its surface can be updated where it changed rather than made whole.
    const FragmentTrees* previous = levelSet ? earlierShapeOf(body) : nullptr;
    FragmentTrees trees;
    trees.madeFrom = body.grid;
    trees.parentId = body.parentId;
    trees.originIjk = previous ? previous->originIjk : body.indexBounds.min();
    const VoxelShape shape{std::make_shared<openvdb::FloatTree>(0.0f), std::make_shared<openvdb::FloatTree>(0.0f)};
    std::vector<VoxelFace> faces;
    faces.reserve(body.exposedFaces.size());
    {
        openvdb::tree::ValueAccessor<openvdb::FloatTree> out(*shape.voxels), fractured(*shape.brokenFaceBits);
        for (auto it = body.grid->constTree().cbeginValueOn(); it; ++it) out.setValueOn(it.getCoord() - trees.originIjk, 1.0f);
        auto links = body.grid->getConstAccessor();
        const Material* material = materialOf(body);
        for (const ExposedFace& f : body.exposedFaces) {
            const openvdb::Coord shifted = f.voxel - trees.originIjk;
            const bool broken = brokenFaceBits(links.getValue(f.voxel)) & (1 << f.face);
            faces.push_back({shifted, f.face, broken});
            if (!broken) continue;
            const int bits = (1 << f.face) | (material && acrossJoint(*material, f.voxel, f.face, body.voxelSizeM) ? 1 << (kJointFaceBit + f.face) : 0);
            fractured.setValueOn(shifted, float(int(fractured.getValue(shifted)) | bits));
        }
    }
    const openvdb::FloatTree::Ptr& voxels = shape.voxels;
    const openvdb::FloatTree::Ptr& fractureFaces = shape.brokenFaceBits;
    const uint64_t shapeHash = contentHash(*voxels), fractureHash = contentHash(*fractureFaces);
    const SurfaceStyle style = surfaceStyle();
    // A rough surface depends on which faces broke too: its key is the voxels with their masks.
    const bool rough = levelSet && style.fractureRoughness > 0.0 && !fractureFaces->empty();
    openvdb::FloatTree::Ptr surfaceKey = voxels;
    if (rough) {
        surfaceKey = std::make_shared<openvdb::FloatTree>(*voxels);
        openvdb::tree::ValueAccessor<openvdb::FloatTree> key(*surfaceKey);
        for (auto it = fractureFaces->cbeginValueOn(); it; ++it) key.setValueOn(it.getCoord(), 1.0f + *it);
    }
    trees.surface = intern(mShapes, surfaceKey, rough ? contentHash(*surfaceKey) : shapeHash, [&] {
        if (!levelSet) return voxels;
        if (previous)
            if (auto updated = updatedVoxelSurfaceLevelSet({previous->shape, previous->surface}, shape, faces.size(), body.voxelSizeM, style)) {
                ++mSurfacesUpdated;
                return updated;
            }
        return voxelSurfaceLevelSet(faces, *voxels, body.voxelSizeM, style);
    });
    if (!fractureFaces->empty()) trees.fractureFaces = intern(mFractureFaces, fractureFaces, fractureHash, [&] { return fractureFaces; });
    trees.meshKey = splitmix64(shapeHash ^ splitmix64(fractureHash));
    // Kept for an update only where one can pay: debris of a few voxels would hold a leaf each.
    if (levelSet && voxels->leafCount() >= kLeastLeavesToUpdate) trees.shape = shape;
    return mShownNow.insert_or_assign(body.id, std::move(trees)).first->second;
}

openvdb::GridBase::Ptr FrameWriter::fragmentGrid(const FrameInfo& info, const Body& body, const FragmentTrees& trees,
                                                 const openvdb::math::Transform::Ptr& voxelMap) const
{
    auto grid = openvdb::FloatGrid::create(trees.surface);
    if (mSettings.fragmentGrids == FragmentGrids::LevelSet) {
        grid->setTransform(levelSetTransform(*voxelMap, mSettings.levelSetSubdivisions));
        grid->setGridClass(openvdb::GRID_LEVEL_SET);
        grid->insertMeta("level_set_half_width", openvdb::FloatMetadata(kLevelSetHalfWidthSamples));
        grid->insertMeta("level_set_subdivisions", openvdb::Int32Metadata(mSettings.levelSetSubdivisions));
    } else {
        grid->setTransform(voxelMap);
        grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    }
    grid->setName("fragment_" + std::to_string(body.id));
    grid->insertMeta("frame", openvdb::Int32Metadata(mSettings.firstFrame + info.frame));
    grid->insertMeta("time_s", openvdb::DoubleMetadata(info.timeS));
    grid->insertMeta("body_id", openvdb::Int64Metadata(body.id));
    grid->insertMeta("parent_id", openvdb::Int64Metadata(body.parentId));
    grid->insertMeta("mass_kg", openvdb::DoubleMetadata(body.mass.massKg));
    grid->insertMeta("voxel_count", openvdb::Int64Metadata(body.mass.voxelCount));
    grid->insertMeta("voxel_size_m", openvdb::DoubleMetadata(body.voxelSizeM));
    grid->insertMeta("mesh_key", openvdb::Int64Metadata(static_cast<int64_t>(trees.meshKey)));
    grid->insertMeta("linear_velocity_m_s", openvdb::Vec3DMetadata(toVdb(body.motion.linearVelocityMS)));
    grid->insertMeta("angular_velocity_rad_s", openvdb::Vec3DMetadata(toVdb(body.motion.angularVelocityRadS)));
    grid->insertMeta("centre_of_mass_m", openvdb::Vec3DMetadata(toVdb(body.motion.positionM)));
    const Eigen::Quaterniond& q = body.motion.orientation;
    grid->insertMeta("orientation_xyzw", openvdb::Vec4DMetadata(openvdb::Vec4d(q.x(), q.y(), q.z(), q.w())));
    grid->insertMeta("anchored", openvdb::BoolMetadata(body.anchored));
    if (const Material* material = materialOf(body)) grid->insertMeta("material", openvdb::StringMetadata(material->name));
    return grid;
}

std::string FrameWriter::write(const FrameInfo& info, const std::vector<Body>& bodies)
{
    const int number = mSettings.firstFrame + info.frame;
    openvdb::GridPtrVec grids;
    std::vector<openvdb::FloatGrid::ConstPtr> levelSets;
    for (const Body& body : bodies) {
        const FragmentTrees& trees = treesOf(body);
        // The trees' voxel (0,0,0) is the body's voxel originIjk.
        auto voxelMap = body.indexToWorld();
        voxelMap->preTranslate(trees.originIjk.asVec3d());
        grids.push_back(fragmentGrid(info, body, trees, voxelMap));
        if (mSettings.debrisLevelSet) levelSets.push_back(openvdb::gridConstPtrCast<openvdb::FloatGrid>(grids.back()));
        if (!trees.fractureFaces) continue;
        auto faces = openvdb::FloatGrid::create(trees.fractureFaces);
        faces->setTransform(voxelMap);
        faces->setName("fracture_faces_" + std::to_string(body.id));
        faces->insertMeta("body_id", openvdb::Int64Metadata(body.id));
        grids.push_back(faces);
    }
    mByBody = std::move(mShownNow);  // the bodies of this frame, for the next
    mShownNow.clear();
    for (auto* pool : {&mShapes, &mFractureFaces})
        for (auto it = pool->begin(); it != pool->end();) {
            const long heldByPool = it->second.derived == it->second.content ? 2 : 1;
            it = it->second.derived.use_count() > heldByPool ? std::next(it) : pool->erase(it);
        }
    const size_t firstWorldGrid = grids.size();
    if ((mSettings.densityGrid || mSettings.velocityGrid) && !bodies.empty()) {
        const WorldGrids world = rasteriseBodies(bodies, bodies.front().voxelSizeM, mSettings.velocityGrid);
        if (mSettings.densityGrid) grids.push_back(world.density);
        if (world.velocity) grids.push_back(world.velocity);
    }
    if (mSettings.debrisLevelSet && !bodies.empty()) {
        grids.push_back(debrisLevelSet(bodies, levelSets));
        grids.back()->setName("debris");
    }
    for (size_t g = firstWorldGrid; g < grids.size(); ++g) {
        grids[g]->insertMeta("frame", openvdb::Int32Metadata(number));
        grids[g]->insertMeta("time_s", openvdb::DoubleMetadata(info.timeS));
    }
    openvdb::MetaMap fileMeta;
    fileMeta.insertMeta("frame", openvdb::Int32Metadata(number));
    fileMeta.insertMeta("first_frame", openvdb::Int32Metadata(mSettings.firstFrame));
    if (info.frameRateHz > 0) fileMeta.insertMeta("frame_rate_hz", openvdb::DoubleMetadata(info.frameRateHz));
    fileMeta.insertMeta("time_s", openvdb::DoubleMetadata(info.timeS));
    fileMeta.insertMeta("spall_version", openvdb::StringMetadata(SPALL_VERSION));
    fileMeta.insertMeta("spall_frame_format", openvdb::Int32Metadata(mSettings.fragmentGrids == FragmentGrids::LevelSet ? kFrameFormatVersion : 1));
    fileMeta.insertMeta("fragment_grids", openvdb::StringMetadata(enumName(mSettings.fragmentGrids)));
    const std::string path = framePath(mDirectory, number);
    writeGridsAtomically(path, grids, fileMeta);
    return path;
}

openvdb::FloatGrid::Ptr FrameWriter::debrisLevelSet(const std::vector<Body>& bodies, const std::vector<openvdb::FloatGrid::ConstPtr>& levelSets)
{
    // Sampled as finely as the pieces' own level sets.
    const double sampleM = bodies.front().voxelSizeM / mSettings.levelSetSubdivisions;
    std::unordered_map<int64_t, WorldPiece> pieces;
    std::vector<size_t> stale;  // the bodies that moved or changed since the last frame
    for (size_t i = 0; i < bodies.size(); ++i) {
        WorldPiece now{levelSets[i]->constTreePtr(), levelSets[i]->transform().baseMap()->getAffineMap()->getMat4(), nullptr};
        const auto cached = mWorldPieces.find(bodies[i].id);
        if (cached != mWorldPieces.end() && cached->second.surface == now.surface && cached->second.indexToWorld == now.indexToWorld)
            now.inWorld = cached->second.inWorld;
        else
            stale.push_back(i);
        pieces.emplace(bodies[i].id, std::move(now));
    }
    std::vector<openvdb::FloatGrid::ConstPtr> resampled(stale.size());
    forEachIndex(stale.size(), [&](size_t s) { resampled[s] = levelSetInWorld(*levelSets[stale[s]], sampleM, kLevelSetHalfWidthSamples); });
    for (size_t s = 0; s < stale.size(); ++s) pieces.at(bodies[stale[s]].id).inWorld = resampled[s];
    mWorldPieces = std::move(pieces);
    std::vector<openvdb::FloatGrid::ConstPtr> inWorld;
    for (const Body& body : bodies) inWorld.push_back(mWorldPieces.at(body.id).inWorld);
    return levelSetUnion(inWorld, sampleM, kLevelSetHalfWidthSamples);
}

std::vector<std::string> listFramePaths(const std::string& outputDirectory)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(outputDirectory, ec)) throw InputError(outputDirectory + ": no such output directory");
    std::vector<std::string> paths;
    for (const auto& entry : fs::directory_iterator(outputDirectory, ec)) {
        const std::string name = entry.path().filename().string();
        // fragments.<digits>.vdb, nothing else (temporaries end in .partial.<pid>).
        if (name.size() < 16 || name.rfind("fragments.", 0) != 0 || name.compare(name.size() - 4, 4, ".vdb") != 0) continue;
        const std::string digits = name.substr(10, name.size() - 14);
        if (!digits.empty() && std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
            paths.push_back(entry.path().string());
    }
    // By number: past 9999 the names grow a digit and no longer sort as text.
    const auto numberOf = [](const std::string& path) { return std::stoll(std::filesystem::path(path).stem().extension().string().substr(1)); };
    std::sort(paths.begin(), paths.end(), [&](const std::string& a, const std::string& b) { return numberOf(a) < numberOf(b); });
    if (paths.empty()) throw InputError(outputDirectory + ": holds no fragments.NNNN.vdb frames (is it a spall run's output?)");
    return paths;
}

WorldGrids rasteriseBodies(const std::vector<Body>& bodies, double h, bool withVelocity)
{
    WorldGrids out;
    out.density = openvdb::FloatGrid::create(0.0f);
    out.density->setTransform(openvdb::math::Transform::createLinearTransform(h));
    out.density->setName("density");
    out.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto density = out.density->getAccessor();
    std::optional<openvdb::Vec3SGrid::Accessor> velocity;
    if (withVelocity) {
        out.velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        out.velocity->setTransform(out.density->transform().copy());
        out.velocity->setName("v");
        out.velocity->setVectorType(openvdb::VEC_INVARIANT);
        velocity.emplace(out.velocity->getAccessor());
    }
    for (const Body& body : bodies) {
        // Visit world voxels in the body's bounding box and look each one up in the body's own
        // index space: no holes, whatever the rotation.
        const Eigen::Matrix3d toLocal = body.motion.orientation.toRotationMatrix().transpose();
        // World box around the body's index box (its eight corners, voxel cubes included).
        const openvdb::CoordBBox& box = body.indexBounds;
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
        for (int c = 0; c < 8; ++c) {
            const Eigen::Vector3d corner((c & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5),
                                         (c & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5),
                                         (c & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5));
            const Eigen::Vector3d world = body.motion.positionM + body.motion.orientation * (corner * h - body.mass.centreOfMassLocalM);
            lo = lo.cwiseMin(world / h);
            hi = hi.cwiseMax(world / h);
        }
        auto in = body.grid->getConstAccessor();
        for (int i = int(std::floor(lo.x())); i <= int(std::ceil(hi.x())); ++i)
            for (int j = int(std::floor(lo.y())); j <= int(std::ceil(hi.y())); ++j)
                for (int k = int(std::floor(lo.z())); k <= int(std::ceil(hi.z())); ++k) {
                    const Eigen::Vector3d world(i * h, j * h, k * h);
                    const Eigen::Vector3d index = (toLocal * (world - body.motion.positionM) + body.mass.centreOfMassLocalM) / h;
                    const openvdb::Coord ijk(int(std::lround(index.x())), int(std::lround(index.y())), int(std::lround(index.z())));
                    if (!in.isValueOn(ijk)) continue;
                    density.setValueOn(openvdb::Coord(i, j, k), 1.0f);
                    if (!velocity) continue;
                    // Rigid motion: v + ω × (x − centre of mass).
                    const Eigen::Vector3d v =
                        body.motion.linearVelocityMS + body.motion.angularVelocityRadS.cross(world - body.motion.positionM);
                    velocity->setValueOn(openvdb::Coord(i, j, k), openvdb::Vec3s(float(v.x()), float(v.y()), float(v.z())));
                }
    }
    return out;
}

}  // namespace spall
