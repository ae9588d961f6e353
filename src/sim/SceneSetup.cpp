// Setting a simulation up: each object's mesh voxelised and placed, anchored to the ground or the
// colliders, and checked (its size against the memory, no charge inside it); the blast field, and
// the static world as the loads and the lattices read it, built once.
#include <spall/sim/Simulation.h>

#include <spall/core/Error.h>
#include <spall/lattice/ParticleBlocks.h>
#include <spall/voxel/VdbIo.h>
#include <spall/sim/MemoryBudget.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace spall {
namespace {


/// Sets the anchor bit of voxels whose lowest point lies within a quarter voxel of the ground.
void anchorToGround(Body& body, const GroundPlane& ground)
{
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (body.voxelHeightAbovePlaneM(it.getCoord(), ground.normal, ground.offsetM) <= 0.25 * body.voxelSizeM) it.setValue(*it | kAnchorBit);
}

/// Sets the anchor bit of voxels with a free face within a quarter voxel of a collider: the
/// centre of the cell beyond the face lies at least a quarter voxel inside the box.
void anchorToColliders(Body& body, const std::vector<ObstacleBox>& boxes)
{
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (freeFaceDeepestInBoxes(body, it.getCoord(), boxes).depthM >= 0.25 * body.voxelSizeM) it.setValue(*it | kAnchorBit);
}

/// An object's primitive at its scale.
Primitive scaledPrimitive(const ObjectSpec& spec)
{
    Primitive primitive = *spec.primitive;
    primitive.sizeM *= spec.scale;
    return primitive;
}

/// An object's extent along its own axes, its mesh already in metres (unit: m).
Eigen::Vector3d objectExtentM(const ObjectSpec& spec, const TriangleMesh& mesh)
{
    if (spec.primitive) return 2.0 * primitiveHalfExtentM(scaledPrimitive(spec));
    Eigen::AlignedBox3f box;
    for (const Eigen::Vector3f& x : mesh.positionsM) box.extend(x);
    return box.isEmpty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(box.sizes().cast<double>());
}

/// "objects[i] ('name') spans X x Y x Z m (mesh_unit u, scale s)", for messages about its size.
std::string describeExtent(const Scene& scene, size_t i, const Eigen::Vector3d& extentM)
{
    const ObjectSpec& spec = scene.objects[i];
    std::ostringstream text;
    text.precision(3);
    text << "objects[" << i << "] ('" << spec.name << "') spans " << extentM.x() << " x " << extentM.y() << " x " << extentM.z() << " m";
    if (!spec.primitive) text << " (mesh_unit \"" << enumName(spec.meshUnit) << "\", scale " << spec.scale << ")";
    return text.str();
}

/// Refuses, before anything is allocated, a scene whose objects' bounding boxes hold more voxels
/// than max_voxels, or whose whole objects would not fit in the memory available; `extentsM` are
/// the objects' (objectExtentM).
void checkSceneFits(const Scene& scene, const std::vector<TriangleMesh>& meshes, const std::vector<Eigen::Vector3d>& extentsM)
{
    const double h = scene.voxelSizeM;
    double upperBound = 0.0;
    size_t largest = 0;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        upperBound += scene.objects[i].primitive ? boundingBoxVoxels(scaledPrimitive(scene.objects[i]), h) : boundingBoxVoxels(meshes[i], h);
        if (extentsM[i].maxCoeff() > extentsM[largest].maxCoeff()) largest = i;
    }
    std::ostringstream problem;
    problem.precision(3);
    if (upperBound > static_cast<double>(scene.maxVoxels)) {
        problem << scene.sourceName << ": max_voxels: the objects' bounding boxes hold up to " << upperBound << " voxels at voxel_size_m "
                << h << ", above max_voxels " << scene.maxVoxels << " (use a larger voxel_size_m: the count falls with its cube); the largest, "
                << describeExtent(scene, largest, extentsM[largest]) << ": a mesh modelled in other units takes mesh_unit (cm, mm, in, ft) or scale";
        throw InputError(problem.str());
    }
    const double needed = estimateMemory(upperBound).intactBytes, available = availableMemoryBytes();
    if (available >= 0 && needed > available) {
        problem << scene.sourceName << ": voxel_size_m: up to " << upperBound << " voxels need about " << needed / 1e9 << " GB, and "
                << available / 1e9 << " GB of memory is available (use a larger voxel_size_m: memory falls with its cube)";
        throw InputError(problem.str());
    }
}

/// The distance from a point to the nearest voxel cube of a body (unit: m).
double nearestVoxelDistanceM(const Body& body, const Eigen::Vector3d& pointM)
{
    const Eigen::Vector3d local = body.motion.orientation.inverse() * (pointM - body.motion.positionM) + body.mass.centreOfMassLocalM;
    double nearestM = std::numeric_limits<double>::infinity();
    for (const openvdb::Coord& v : body.boundaryVoxels) {
        const Eigen::Vector3d centre = Eigen::Vector3d(v.x(), v.y(), v.z()) * body.voxelSizeM;
        const Eigen::Vector3d outside = ((local - centre).cwiseAbs().array() - 0.5 * body.voxelSizeM).max(0.0).matrix();
        nearestM = std::min(nearestM, outside.norm());
    }
    return nearestM;
}

/// A charge under the ground or inside a collider is buried: the blast model is of charges in
/// air or on the surface (Kingery–Bulmash), so it would run as one there, silently.
void refuseBuriedCharges(const Scene& scene, const StaticWorld& world)
{
    constexpr double kToleranceM = 1e-6;
    for (size_t c = 0; c < scene.charges.size(); ++c) {
        const Eigen::Vector3d& x = scene.charges[c].positionM;
        const std::string key = scene.sourceName + ": charges[" + std::to_string(c) + "].position_m: ";
        const double heightM = world.ground.enabled ? world.ground.normal.dot(x) - world.ground.offsetM : 0.0;
        if (heightM < -kToleranceM)
            throw InputError(key + "the charge is " + std::to_string(-heightM) + " m below the ground; the blast model is of charges in air "
                             "or on the surface (a surface burst sits on the ground: height 0)");
        for (size_t b = 0; b < world.boxes.size(); ++b)
            if (depthInsideM(world.boxes[b], x) > kToleranceM)
                throw InputError(key + "the charge is inside colliders[" + std::to_string(b) + "]; the blast model is of charges in air or on "
                                 "the surface");
    }
}

/// A charge inside an object would need contact detonation physics the model does not have.
void refuseChargesInside(const Body& body, const std::string& objectName, const Scene& scene)
{
    for (size_t c = 0; c < scene.charges.size(); ++c) {
        const Eigen::Vector3d local = (body.motion.orientation.inverse() * (scene.charges[c].positionM - body.motion.positionM) +
                                       body.mass.centreOfMassLocalM) / body.voxelSizeM;
        const openvdb::Coord ijk(static_cast<int>(std::lround(local.x())), static_cast<int>(std::lround(local.y())),
                                 static_cast<int>(std::lround(local.z())));
        if (body.grid->tree().isValueOn(ijk))
            throw InputError(scene.sourceName + ": charges[" + std::to_string(c) + "].position_m: the charge is inside object '" + objectName + "'");
    }
}

/// The free field: the scene's charges, with the ground's reflection of those in free air.
std::unique_ptr<BlastField> makeField(const Scene& scene)
{
    const GroundPlane& ground = scene.world.ground;
    std::vector<Charge> charges = ground.enabled ? withGroundImages(scene.charges, ground.normal, ground.offsetM) : scene.charges;
    // Weakening remembers which charge loaded a link in a few bits of the link's value.
    const bool weakening = scene.fracture.algorithm == FractureAlgorithm::YieldLimit && scene.fracture.weakening;
    if (weakening && charges.size() > static_cast<size_t>(kMaxWeakeningCharges))
        throw InputError(scene.sourceName + ": charges: " + std::to_string(charges.size()) + " charges (ground images included) with "
                         "fracture.weakening on; it tells at most " + std::to_string(kMaxWeakeningCharges) +
                         " apart (set fracture.weakening to false, or merge charges)");
    return std::make_unique<BlastField>(std::move(charges), scene.blast);
}

}  // namespace

Simulation::Simulation(const Scene& scene, Interrupter* interrupter) : mScene(scene)
{
    initialiseOpenVdb();
    mField = makeField(scene);
    mStaticWorld = buildStaticWorld(scene.world.ground, scene.world.colliders, scene.world.gravityMS2);
    refuseBuriedCharges(scene, mStaticWorld);
    const std::vector<TriangleMesh> meshes = loadMeshes();
    std::vector<Eigen::Vector3d> extentsM;
    for (size_t i = 0; i < scene.objects.size(); ++i) extentsM.push_back(objectExtentM(scene.objects[i], meshes[i]));
    noteImplausibleMeshSizes(extentsM);
    checkSceneFits(scene, meshes, extentsM);
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        Body body = placeObject(i, voxeliseObject(scene.objects[i], meshes[i], interrupter));
        mState.initialVoxels += body.mass.voxelCount;
        if (scene.fracture.algorithm == FractureAlgorithm::DavisonStevens) body.damage = zeroDamageLike(*body.grid);
        mState.bodies.push_back(std::move(body));
    }
    noteFragmentMemory();
    noteFractureLimits();
    noteUnresolvedThickness();
    noteChargesNearerThanTheBlastData();
    noteDeformablePhaseCost();
    mState.stepStats.minDtS = scene.timeStep.maxTimeStepS;
}

std::vector<TriangleMesh> Simulation::loadMeshes()
{
    std::vector<TriangleMesh> meshes(mScene.objects.size());
    for (size_t i = 0; i < mScene.objects.size(); ++i) {
        if (mScene.objects[i].primitive) continue;
        std::vector<std::string> notes;
        meshes[i] = loadMesh(mScene.objects[i].meshPath, &notes);
        for (const std::string& note : notes) mNotes.push_back(mScene.objects[i].meshPath + ": " + note);
        const float unitM = float(objectUnitM(mScene.objects[i]));
        if (unitM != 1.0f)
            for (Eigen::Vector3f& x : meshes[i].positionsM) x *= unitM;
    }
    return meshes;
}

void Simulation::noteImplausibleMeshSizes(const std::vector<Eigen::Vector3d>& extentsM)
{
    // Larger than any building's wall or smaller than a brick's joint: likely the wrong unit.
    constexpr double kLargestM = 100.0, kSmallestM = 0.01;
    for (size_t i = 0; i < extentsM.size(); ++i) {
        const double largestM = extentsM[i].maxCoeff();
        if (mScene.objects[i].primitive || (largestM <= kLargestM && largestM >= kSmallestM)) continue;
        mNotes.push_back(describeExtent(mScene, i, extentsM[i]) + ", " + (largestM > kLargestM ? "larger" : "smaller") +
                         " than a structure spall is made for: a mesh modelled in other units takes mesh_unit (cm, mm, in, ft) or scale");
    }
}

VoxeliseResult Simulation::voxeliseObject(const ObjectSpec& spec, const TriangleMesh& mesh, Interrupter* interrupter)
{
    VoxeliseSettings vs;
    vs.voxelSizeM = mScene.voxelSizeM;
    vs.maxVoxels = mScene.maxVoxels - mState.initialVoxels;  // the limit is the scene's, over all objects
    vs.insideTest = spec.inside;
    vs.shellThicknessM = spec.shellThicknessM;
    VoxeliseResult vox = spec.primitive ? voxelisePrimitive(scaledPrimitive(spec), vs) : voxeliseMesh(mesh, vs, spec.meshPath, interrupter);
    for (const std::string& note : vox.notes) mNotes.push_back(spec.meshPath + ": " + note);
    return vox;
}

Body Simulation::placeObject(size_t index, const VoxeliseResult& vox)
{
    const ObjectSpec& spec = mScene.objects[index];
    const Material material = mScene.material(spec.material);
    validateMaterial(material);
    Body body = makeBody(vox.grid, mScene.voxelSizeM, material.densityKgM3);
    body.id = mState.nextId++;
    const auto known = std::find_if(mScene.materials.begin(), mScene.materials.end(), [&](const Material& m) { return m.name == spec.material; });
    body.materialIndex = static_cast<int>(known - mScene.materials.begin());
    if (known == mScene.materials.end()) mScene.materials.push_back(material);  // a preset the scene did not list
    // world = t + Q (index h + offset): the centre of mass goes to t + Q (c + offset).
    body.motion.orientation = rotationFromDegrees(spec.rotationDeg);
    body.motion.positionM = spec.positionM + body.motion.orientation * (body.mass.centreOfMassLocalM + vox.localOffsetM);
    if (spec.anchor != AnchorMode::None) {
        if (spec.anchor == AnchorMode::Ground || mScene.world.ground.enabled) anchorToGround(body, mScene.world.ground);
        if (spec.anchor == AnchorMode::Supports) anchorToColliders(body, mStaticWorld.boxes);
        refreshDerivedData(body);
        body.motion.positionM = spec.positionM + body.motion.orientation * (body.mass.centreOfMassLocalM + vox.localOffsetM);
        if (!body.anchored)
            throw InputError(mScene.sourceName + ": objects[" + std::to_string(index) + "].anchor: no voxel of '" + spec.name + "' touches the ground" +
                             (spec.anchor == AnchorMode::Supports ? " or a collider" : ""));
    }
    if (body.anchored && !(spec.linearVelocityMS.isZero(0.0) && spec.angularVelocityRadS.isZero(0.0)))
        throw InputError(mScene.sourceName + ": objects[" + std::to_string(index) + "]: '" + spec.name +
                         "' is anchored and cannot start moving (linear_velocity_m_s, angular_velocity_rad_s)");
    body.motion.linearVelocityMS = spec.linearVelocityMS;
    body.motion.angularVelocityRadS = spec.angularVelocityRadS;
    refuseChargesInside(body, spec.name, mScene);
    return body;
}

void Simulation::noteFragmentMemory()
{
    const double available = availableMemoryBytes();
    const double allBroken = estimateMemory(static_cast<double>(mState.initialVoxels)).allBrokenBytes;
    if (available < 0 || allBroken <= available) return;
    std::ostringstream note;
    note.precision(3);
    note << "if all " << mState.initialVoxels << " voxels broke free (the fracture rules can do that under a strong blast) "
         << "the run would need about " << allBroken / 1e9 << " GB, and " << available / 1e9
         << " GB is available: a larger voxel_size_m needs fewer (memory falls with its cube)";
    mNotes.push_back(note.str());
}

namespace {

/// The lattice's cost and size on 2 cores, measured on the 3 M-voxel brick wall at 1 cm
/// (docs/performance.md, "A 3 M-voxel wall"): 4.6–5.8 M particle-steps a second in a run, and
/// 277 B a particle plus 136 B for each of its three bonds.
constexpr double kLatticeParticleStepsPerS = 5e6;
constexpr double kLatticeBytesPerParticle = 277.0 + 3.0 * 136.0;
/// A run whose deformable phase could take longer than this, or more memory, is told so first.
constexpr double kLatticeCostWorthANoteS = 300.0;
constexpr double kLatticeMemoryWorthANoteBytes = 1e9;

/// How many lattice particles the body makes in blocks of k³ voxels (ParticleBlocks.h).
double particleCount(const Body& body, int k)
{
    if (k == 1) return double(body.mass.voxelCount);
    const VoxelBlocks blocks = blocksFor(body, k);
    openvdb::MaskGrid cells;
    auto cell = cells.getAccessor();
    for (auto it = body.grid->cbeginValueOn(); it; ++it) cell.setValueOn(particleCell(it.getCoord(), blocks));
    return double(cells.activeVoxelCount());
}

}  // namespace

void Simulation::noteDeformablePhaseCost()
{
    if (mScene.fracture.algorithm != FractureAlgorithm::Lattice || mScene.charges.empty()) return;
    const int k = mScene.lattice.particleVoxels;
    const double particleM = mScene.voxelSizeM * k;
    double particles = 0.0, particleSteps = 0.0;
    for (size_t i = 0; i < mState.bodies.size(); ++i) {
        const Material& material = mScene.material(mScene.objects[i].material);
        // The particles share the body's mass (coarsenedBody).
        const double count = particleCount(mState.bodies[i], k);
        const double stepS = stableTimeStepS(calibrateLattice(material, particleM), particleM, mState.bodies[i].mass.massKg / count);
        // A body stays in the phase while the blast acts on it and at most max_vibration_s after.
        double blastS = 0.0;
        for (const Charge& charge : mScene.charges) {
            const double distanceM = nearestVoxelDistanceM(mState.bodies[i], charge.positionM);
            if (distanceM > 0.0)
                blastS = std::max(blastS, blastParameters(mScene.blast.dataset, charge.burst, charge.tntKg, distanceM, mScene.blast.atmosphere).positiveDurationS);
        }
        particles += count;
        particleSteps += count * std::ceil((blastS + mScene.lattice.maxVibrationS) / stepS);
    }
    const double seconds = particleSteps / kLatticeParticleStepsPerS, bytes = particles * kLatticeBytesPerParticle;
    if (seconds < kLatticeCostWorthANoteS && bytes < kLatticeMemoryWorthANoteBytes) return;
    std::ostringstream note;
    note.precision(3);
    note << "the deformable phase may take up to " << particleSteps << " particle-steps (" << std::llround(particles) << " lattice particles): about "
         << seconds / 60.0 << " min at the " << kLatticeParticleStepsPerS / 1e6 << " M particle-steps a second measured on 2 cores "
         << "(docs/performance.md), and " << bytes / 1e9 << " GB for its lattices. lattice.max_vibration_s (" << mScene.lattice.maxVibrationS
         << " s) bounds a body's time in the phase; lattice.particle_voxels k (" << k << ") steps blocks of k^3 voxels, about k^4 times "
         << "less work; a larger voxel_size_m, less still";
    mNotes.push_back(note.str());
}

void Simulation::noteChargesNearerThanTheBlastData()
{
    for (size_t c = 0; c < mScene.charges.size(); ++c) {
        const Charge& charge = mScene.charges[c];
        for (size_t i = 0; i < mState.bodies.size(); ++i) {
            const double distanceM = nearestVoxelDistanceM(mState.bodies[i], charge.positionM);
            if (!(distanceM > 0.0)) continue;
            const BlastParameters p = blastParameters(mScene.blast.dataset, charge.burst, charge.tntKg, distanceM, mScene.blast.atmosphere);
            if (p.status != RangeStatus::ClampedNear) continue;
            std::ostringstream note;
            note.precision(3);
            note << "charges[" << c << "] is " << distanceM << " m from objects[" << i << "] ('" << mScene.objects[i].name << "'), scaled distance "
                 << p.scaledDistanceMKg13 << " m/kg^(1/3), nearer than the blast data's fits reach (" << enumName(mScene.blast.dataset) << ", "
                 << enumName(charge.burst) << "): its pressures there are held at the fits' near end, so the nearest faces' loads are "
                 << "underestimated; the model is of charges in air, not in contact";
            mNotes.push_back(note.str());
        }
    }
}

void Simulation::noteFractureLimits()
{
    const FractureAlgorithm algorithm = mScene.fracture.algorithm;
    if (algorithm == FractureAlgorithm::YieldLimit || algorithm == FractureAlgorithm::DavisonStevens)
        mNotes.push_back("fracture.algorithm \"" + std::string(enumName(algorithm)) +
                         "\" is one of the paper's rules (Mazarak et al. 1999), kept as a baseline: links break on the blast's pressure "
                         "where they are, whatever its impulse and whatever shields them; \"lattice\" breaks them by the stress the loads "
                         "put into the material");
    if (algorithm != FractureAlgorithm::Lattice) return;
    noteRateDamageWithoutRateLaw();
    const double particleM = mScene.voxelSizeM * mScene.lattice.particleVoxels;
    for (size_t i = 0; i < mScene.objects.size(); ++i) {
        const Material& material = mScene.material(mScene.objects[i].material);
        if (!hasUnits(material) || unitsResolvedBy(material, particleM)) continue;
        const double courseM = material.unitHeightM + material.jointThicknessM;
        std::ostringstream note;
        note.precision(3);
        note << "objects[" << i << "] ('" << mScene.objects[i].name << "', " << material.name << "): its lattice's particles (" << particleM
             << " m: voxel_size_m x lattice.particle_voxels) are taller than a course (" << courseM
             << " m), so it breaks as homogenised masonry, along its bed joints at their strength and across its courses at "
             << acrossCoursesStrengthRatio(material) << " times it, into pieces no smaller than a particle; particles of at most "
             << courseM << " m resolve its units";
        mNotes.push_back(note.str());
    }
}

void Simulation::noteRateDamageWithoutRateLaw()
{
    if (mScene.lattice.damageLaw != LatticeDamageLaw::DavisonStevens) return;
    for (size_t i = 0; i < mScene.objects.size(); ++i) {
        const Material& material = mScene.material(mScene.objects[i].material);
        if (material.strengthRateLaw != StrengthRateLaw::None) continue;
        mNotes.push_back("objects[" + std::to_string(i) + "] ('" + mScene.objects[i].name + "', " + material.name +
                         "): lattice.damage_law \"davison-stevens\" is fitted to a material's strain-rate law, and this material has "
                         "none (its strength_rate_law is \"none\"), so its bonds soften on the crack band's line, rate-free");
    }
}

void Simulation::noteUnresolvedThickness()
{
    if (mScene.fracture.algorithm != FractureAlgorithm::Lattice) return;
    const double particleM = mScene.voxelSizeM * mScene.lattice.particleVoxels;
    for (size_t i = 0; i < mState.bodies.size(); ++i) {
        const std::string object = "objects[" + std::to_string(i) + "] ('" + mScene.objects[i].name + "')";
        const openvdb::Coord extent = mState.bodies[i].grid->evalActiveVoxelBoundingBox().dim();
        const double thinnestM = mScene.voxelSizeM * std::min({extent.x(), extent.y(), extent.z()});
        std::ostringstream note;
        note.precision(3);
        if (thinnestM <= 2.0 * particleM) {
            note << object << " is " << thinnestM / particleM << " particles across its thinnest side (" << thinnestM
                 << " m): the stress across it, which bends and spalls it, is not resolved; voxel_size_m x lattice.particle_voxels of at most "
                 << thinnestM / 4.0 << " m puts four particles across";
            mNotes.push_back(note.str());
            continue;
        }
        const double spallM = shallowestSpallZoneM(i);
        if (spallM > 0.0 && spallM < particleM) {
            note << object << ": the nearest charge's reflected pulse would spall its far face to about " << spallM
                 << " m deep (half the pulse's length in the material: Rinehart 1960), less than its particles (" << particleM
                 << " m), which cannot resolve it; particles of at most " << spallM / 2.0 << " m put two across it";
            mNotes.push_back(note.str());
        }
    }
}

double Simulation::shallowestSpallZoneM(size_t bodyIndex) const
{
    // A compressive pulse of peak σ0 and length L = c t (UFC 3-340-02's fictitious triangular
    // duration t = 2 Ir / Pr, c the P-wave speed) reflects from the far face as tension, which
    // exceeds ft from L ft / (2 σ0) to L / 2 from the face (Rinehart 1960, a sawtooth pulse):
    // the spalled zone, about L / 2 deep once σ0 is well above ft. None when σ0 stays below ft.
    const Body& body = mState.bodies[bodyIndex];
    const Material& m = mScene.materials[body.materialIndex];
    const double waveSpeedMS = pWaveSpeedMS(m);
    double shallowestM = 0.0;
    for (const Charge& charge : mScene.charges) {
        const double distanceM = nearestVoxelDistanceM(body, charge.positionM);
        if (!(distanceM > 0.0)) continue;
        const BlastParameters p = blastParameters(mScene.blast.dataset, charge.burst, charge.tntKg, distanceM, mScene.blast.atmosphere);
        if (p.reflectedPressurePa <= m.tensileStrengthPa) continue;
        const double depthM = waveSpeedMS * p.reflectedImpulsePaS / p.reflectedPressurePa;  // L / 2
        shallowestM = shallowestM > 0.0 ? std::min(shallowestM, depthM) : depthM;
    }
    return shallowestM;
}

Simulation::Simulation(const Scene& scene, SimulationState state) : mScene(scene), mState(std::move(state))
{
    requireVoxelSize(mState.bodies, scene.voxelSizeM);
    initialiseOpenVdb();
    mField = makeField(scene);
    mStaticWorld = buildStaticWorld(scene.world.ground, scene.world.colliders, scene.world.gravityMS2);
    // A saved lattice holds its state; its bonds and stiffness follow from its body again.
    mState.deformable.reindex(mState.bodies);
    for (size_t k = 0; k < mState.deformable.lattices.size(); ++k) {
        const Body& body = mState.bodies[mState.deformable.bodyIndex(k, mState.bodies)];
        restoreDeformable(mState.deformable.lattices[k], body, mScene.materials[body.materialIndex], mScene.lattice, mStaticWorld, mScene.seed);
    }
}

Simulation rigidBodySimulation(std::vector<Body> bodies, const WorldSettings& world, const CollisionSettings& collisions,
                               const SleepSettings& sleep, double maxStepS, bool fixedStep)
{
    Scene scene;
    scene.world = world;
    scene.collisions = collisions;
    scene.sleep = sleep;
    scene.fracture.algorithm = FractureAlgorithm::None;
    scene.timeStep.maxTimeStepS = maxStepS;
    if (fixedStep) scene.timeStep.minTimeStepS = maxStepS;
    if (!bodies.empty()) scene.voxelSizeM = bodies.front().voxelSizeM;
    SimulationState state;
    state.bodies = std::move(bodies);
    return Simulation(scene, std::move(state));
}


}  // namespace spall
