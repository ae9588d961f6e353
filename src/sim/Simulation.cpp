#include <spall/sim/Simulation.h>

#include <spall/core/Error.h>
#include <spall/dynamics/Integrate.h>
#include <spall/dynamics/Sleep.h>
#include <spall/io/VdbIo.h>
#include <spall/loads/BlastLoads.h>
#include <spall/loads/Exposure.h>
#include <spall/sim/MemoryBudget.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <sstream>

namespace spall {

namespace {

ObstacleBox obstacleOf(const StaticBox& box) { return {box.centreM, box.halfExtentM, box.orientation}; }

/// Sets the anchor bit of voxels whose lowest point lies within a quarter voxel of the ground.
void anchorToGround(Body& body, const GroundPlane& ground)
{
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (body.voxelHeightAbovePlaneM(it.getCoord(), ground.normal, ground.offsetM) <= 0.25 * body.voxelSizeM) it.setValue(*it | kAnchorBit);
}

/// Sets the anchor bit of voxels with a free face within a quarter voxel of a collider: the
/// centre of the cell beyond the face lies at least a quarter voxel inside the box.
void anchorToColliders(Body& body, const std::vector<StaticBox>& colliders)
{
    std::vector<ObstacleBox> boxes;
    for (const StaticBox& box : colliders) boxes.push_back(obstacleOf(box));
    for (auto it = body.grid->beginValueOn(); it; ++it)
        if (freeFaceDeepestInBoxes(body, it.getCoord(), boxes).depthM >= 0.25 * body.voxelSizeM) it.setValue(*it | kAnchorBit);
}

/// Refuses, before anything is allocated, a scene whose objects' bounding boxes hold more voxels
/// than max_voxels, or whose whole objects would not fit in the memory available.
void checkSceneFits(const Scene& scene, const std::vector<TriangleMesh>& meshes)
{
    const double h = scene.voxelSizeM;
    double upperBound = 0.0;
    for (size_t i = 0; i < scene.objects.size(); ++i)
        upperBound += scene.objects[i].primitive ? boundingBoxVoxels(*scene.objects[i].primitive, h) : boundingBoxVoxels(meshes[i], h);
    std::ostringstream problem;
    problem.precision(3);
    if (upperBound > static_cast<double>(scene.maxVoxels)) {
        problem << scene.sourceName << ": max_voxels: the objects' bounding boxes hold up to " << upperBound << " voxels at voxel_size_m "
                << h << ", above max_voxels " << scene.maxVoxels << " (use a larger voxel_size_m: the count falls with its cube)";
        throw InputError(problem.str());
    }
    const double needed = estimateMemory(upperBound).intactBytes, available = availableMemoryBytes();
    if (available >= 0 && needed > available) {
        problem << scene.sourceName << ": voxel_size_m: up to " << upperBound << " voxels need about " << needed / 1e9 << " GB, and "
                << available / 1e9 << " GB of memory is available (use a larger voxel_size_m: memory falls with its cube)";
        throw InputError(problem.str());
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
    const std::vector<TriangleMesh> meshes = loadMeshes();
    checkSceneFits(scene, meshes);
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        Body body = placeObject(i, voxeliseObject(scene.objects[i], meshes[i], interrupter));
        mState.initialVoxels += body.mass.voxelCount;
        if (scene.fracture.algorithm == FractureAlgorithm::DavisonStevens) body.damage = zeroDamageLike(*body.grid);
        mState.bodies.push_back(std::move(body));
    }
    noteFragmentMemory();
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
    }
    return meshes;
}

VoxeliseResult Simulation::voxeliseObject(const ObjectSpec& spec, const TriangleMesh& mesh, Interrupter* interrupter)
{
    VoxeliseSettings vs;
    vs.voxelSizeM = mScene.voxelSizeM;
    vs.maxVoxels = mScene.maxVoxels - mState.initialVoxels;  // the limit is the scene's, over all objects
    vs.insideTest = spec.inside;
    vs.shellThicknessM = spec.shellThicknessM;
    VoxeliseResult vox = spec.primitive ? voxelisePrimitive(*spec.primitive, vs) : voxeliseMesh(mesh, vs, spec.meshPath, interrupter);
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
        if (spec.anchor == AnchorMode::Supports) anchorToColliders(body, mScene.world.colliders);
        refreshDerivedData(body);
        body.motion.positionM = spec.positionM + body.motion.orientation * (body.mass.centreOfMassLocalM + vox.localOffsetM);
        if (!body.anchored)
            throw InputError(mScene.sourceName + ": objects[" + std::to_string(index) + "].anchor: no voxel of '" + spec.name + "' touches the ground" +
                             (spec.anchor == AnchorMode::Supports ? " or a collider" : ""));
    }
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

Simulation::Simulation(const Scene& scene, SimulationState state) : mScene(scene), mState(std::move(state))
{
    requireVoxelSize(mState.bodies, scene.voxelSizeM);
    initialiseOpenVdb();
    mField = makeField(scene);
    // A saved lattice holds its state; its bonds and stiffness follow from its body again.
    for (DeformableBody& d : mState.deformable) {
        const auto body = std::find_if(mState.bodies.begin(), mState.bodies.end(), [&](const Body& b) { return b.id == d.bodyId; });
        if (body == mState.bodies.end()) throw InputError("saved state: deformable body " + std::to_string(d.bodyId) + " is not among the bodies");
        restoreDeformable(d, *body, mScene.materials[body->materialIndex], mScene.lattice, latticeSupports());
    }
}

LatticeSupports Simulation::latticeSupports() const
{
    const GroundPlane& g = mScene.world.ground;
    LatticeSupports supports{{g.enabled, g.normal.normalized(), g.offsetM}, {}, {}};
    for (const StaticBox& box : mScene.world.colliders) {
        supports.boxes.push_back(obstacleOf(box));
        supports.pinned.push_back(box.holds == SupportHold::Pinned ? 1 : 0);
    }
    return supports;
}

StepStats Simulation::takeStepStats()
{
    StepStats s = mState.stepStats;
    mState.stepStats = StepStats();
    mState.stepStats.minDtS = mScene.timeStep.maxTimeStepS;
    return s;
}

bool Simulation::advanceTo(double targetS, Interrupter* interrupter, const std::function<void()>& afterStep)
{
    while (mState.timeS < targetS) {
        if (interrupter && interrupter->wasInterrupted()) return false;
        step(targetS);
        if (afterStep) afterStep();
    }
    return true;
}

void Simulation::step(double targetS)
{
    const std::vector<OpenWindow> windows = mField->openWindows(mState.timeS);
    // Choose dt, landing exactly on the target without a sliver of a step just before it.
    const double remaining = targetS - mState.timeS;
    const double chosen = chooseTimeStep(windows);
    const bool last = chosen >= remaining;
    const double dt = last ? remaining : remaining < 2.0 * chosen ? 0.5 * remaining : chosen;
    if (mObserver) {
        mRecord = StepRecord{0.0, dt, false};
        for (const Body& body : mState.bodies) mRecord.blastOpen = mRecord.blastOpen || bodyInWindows(body, *mField, windows);
    }

    const std::vector<char> cracked = fractureBodies(windows, dt);
    splitBodies(cracked);
    handOffQuietBodies(dt);
    enterDeformablePhase(windows);

    LoadGeometry geometry{{mScene.world.ground.enabled, mScene.world.ground.normal.normalized(), mScene.world.ground.offsetM}, {}};
    for (const StaticBox& box : mScene.world.colliders) geometry.obstacles.push_back(obstacleOf(box));
    const BlastLoads blast(*mField, windows, mScene.loads, geometry);
    const std::vector<char> loaded = blast.loadedBodies(mState.bodies);
    wakeLoadedBodies(mState.bodies, loaded);
    FaceForces faces;
    for (const Body& body : mState.bodies) faces.wanted.push_back(body.motion.deformable);
    const std::vector<Wrench> blastWrenches = blast.stepWrenches(mState.bodies, loaded, mState.timeS, dt, &faces);
    integrateBodies(mState.bodies, blastWrenches, mScene.world, airOf(mScene.blast.atmosphere), mScene.timeStep.integrator, mState.timeS, dt);
    deformBodies(faces, windows, dt);

    const ContactSet contacts = detectContacts(mState.bodies, mScene.world, mScene.collisions, mScene.sleep);
    const double closingPenetrationM = deepestClosingPenetrationM(mState.bodies, contacts, tunnellingSpeedMS(mScene.world, dt, mScene.voxelSizeM));
    solveContactsWithLattices(contacts, dt);
    correctPositions(mState.bodies, contacts, mScene.world);
    updateSleep(mState.bodies, contacts.touching, loaded, mScene.sleep, dt);
    adaptStepToPenetration(closingPenetrationM);
    refuseNonFiniteMotion();
    if (mObserver) mRecord.solverContacts = contacts.solverContacts;

    mState.timeS = last ? targetS : mState.timeS + dt;
    ++mState.stepStats.steps;
    mState.stepStats.minDtS = std::min(mState.stepStats.minDtS, dt);
    if (mObserver) {
        mRecord.timeS = mState.timeS;
        mObserver(*this, mRecord);
    }
}

void Simulation::refuseNonFiniteMotion() const
{
    for (const Body& body : mState.bodies) {
        const BodyMotion& m = body.motion;
        if (m.positionM.allFinite() && m.orientation.coeffs().allFinite() && m.linearVelocityMS.allFinite() && m.angularVelocityRadS.allFinite())
            continue;
        throw SimulationError("body " + std::to_string(body.id) + " has a non-finite position or velocity at t = " +
                              std::to_string(mState.timeS) + " s: the integration became unstable (a smaller solver.max_time_step_s may help)");
    }
}

std::vector<char> Simulation::fractureBodies(const std::vector<OpenWindow>& windows, double dt)
{
    std::vector<char> cracked(mState.bodies.size(), 0);
    // The lattice breaks its bonds itself (deformBodies).
    if (windows.empty() || mScene.fracture.algorithm == FractureAlgorithm::None || mScene.fracture.algorithm == FractureAlgorithm::Lattice)
        return cracked;
    // The pressure table is built only when some body can fracture inside a window: windows
    // stay open far away long after the blast has passed every body.
    std::optional<PressureSnapshot> pressure;
    for (size_t i = 0; i < mState.bodies.size(); ++i) {
        Body& body = mState.bodies[i];
        if (body.linkCount == 0 && !body.anchored) continue;
        if (!bodyInWindows(body, *mField, windows)) continue;
        if (!pressure) pressure.emplace(*mField, mState.timeS, dt);
        const LoadResult r = loadLinks(body, mScene.materials[body.materialIndex], *pressure, dt, mScene.fracture);
        mState.stepStats.brokenLinks += r.brokenLinks;
        cracked[i] = r.brokenLinks > 0 || r.brokenAnchors > 0;
    }
    return cracked;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> Simulation::totalMomenta() const
{
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    for (const Body& b : mState.bodies) {
        linear += linearMomentum(b);
        angular += angularMomentumAboutOrigin(b);
    }
    for (const DustRecord& d : mState.dust) {
        linear += d.linearMomentum;
        angular += d.angularMomentumAboutOrigin;
    }
    return {linear, angular};
}

void Simulation::splitBodies(const std::vector<char>& cracked)
{
    if (std::none_of(cracked.begin(), cracked.end(), [](char c) { return c; })) return;
    if (mObserver) std::tie(mRecord.linearMomentumBeforeSplit, mRecord.angularMomentumBeforeSplit) = totalMomenta();
    std::vector<std::vector<Body>> parts(mState.bodies.size());
    for (size_t i = 0; i < mState.bodies.size(); ++i)
        if (cracked[i]) parts[i] = splitBody(mState.bodies[i]);
    replaceWithParts(parts);
    if (mObserver) {
        mRecord.split = true;
        std::tie(mRecord.linearMomentumAfterSplit, mRecord.angularMomentumAfterSplit) = totalMomenta();
    }
}

void Simulation::replaceWithParts(std::vector<std::vector<Body>>& parts)
{
    std::vector<Body> next;
    next.reserve(mState.bodies.size());
    for (size_t i = 0; i < mState.bodies.size(); ++i) {
        if (parts[i].empty()) {
            next.push_back(std::move(mState.bodies[i]));
            continue;
        }
        FractureEvent event;
        event.timeS = mState.timeS;
        event.parentId = mState.bodies[i].id;
        for (Body& part : parts[i]) {
            const bool small = part.mass.voxelCount < mScene.fracture.minFragmentVoxels;
            if (small && mScene.fracture.smallFragments == SmallFragmentPolicy::Dust && !part.anchored) {
                mState.dust.push_back({mState.timeS, mState.bodies[i].id, part.mass.voxelCount, part.mass.massKg, linearMomentum(part),
                                       angularMomentumAboutOrigin(part)});
                continue;
            }
            part.id = mState.nextId++;
            event.childIds.push_back(part.id);
            next.push_back(std::move(part));
        }
        mState.events.push_back(std::move(event));
    }
    mState.bodies = std::move(next);
}

void Simulation::enterDeformablePhase(const std::vector<OpenWindow>& windows)
{
    if (mScene.fracture.algorithm != FractureAlgorithm::Lattice || windows.empty()) return;
    for (Body& body : mState.bodies) {
        if (body.motion.deformable || (body.linkCount == 0 && !body.anchored) || !bodyInWindows(body, *mField, windows)) continue;
        mState.deformable.push_back(
            spall::enterDeformablePhase(body, mScene.materials[body.materialIndex], mScene.lattice, latticeSupports(), mState.timeS));
        body.motion.deformable = true;
        body.motion.asleep = false;
        body.motion.restTimeS = 0.0;
    }
}

void Simulation::deformBodies(const FaceForces& faces, const std::vector<OpenWindow>& windows, double dtS)
{
    if (mState.deformable.empty()) return;
    const std::unordered_map<int64_t, size_t> indexOf = bodyIndexById();
    for (DeformableBody& d : mState.deformable) {
        const size_t i = indexOf.at(d.bodyId);
        Body& body = mState.bodies[i];
        setExternalForces(d, body, faces.forceN[i], mScene.world.gravityMS2);
        mState.stepStats.latticeParticleSteps += advanceDeformable(d, dtS);
        followLattice(body, d.lattice);
        if (bodyInWindows(body, *mField, windows)) d.lastLoadedS = mState.timeS + dtS;
    }
}

std::unordered_map<int64_t, size_t> Simulation::bodyIndexById() const
{
    std::unordered_map<int64_t, size_t> indexOf;
    for (size_t i = 0; i < mState.bodies.size(); ++i) indexOf[mState.bodies[i].id] = i;
    return indexOf;
}

void Simulation::solveContactsWithLattices(const ContactSet& contacts, double dtS)
{
    std::vector<size_t> latticeBody;
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> before;
    if (!mState.deformable.empty()) {
        const std::unordered_map<int64_t, size_t> indexOf = bodyIndexById();
        for (const DeformableBody& d : mState.deformable) {
            latticeBody.push_back(indexOf.at(d.bodyId));
            const Body& body = mState.bodies[latticeBody.back()];
            before.emplace_back(linearMomentum(body), angularMomentumAboutOrigin(body));
        }
    }
    solveContacts(mState.bodies, contacts, mScene.world, mScene.collisions, dtS, mState.contactCache);
    for (size_t k = 0; k < latticeBody.size(); ++k) {
        Body& body = mState.bodies[latticeBody[k]];
        if (!takesContactImpulses(body)) continue;
        const Eigen::Vector3d linear = linearMomentum(body) - before[k].first, angular = angularMomentumAboutOrigin(body) - before[k].second;
        if (linear.isZero(0.0) && angular.isZero(0.0)) continue;  // no contact moved it
        DeformableBody& d = mState.deformable[k];
        addRigidMomentum(d.lattice, linear, angular);
        followLattice(body, d.lattice);
    }
}

void Simulation::handOffQuietBodies(double dtS)
{
    if (mState.deformable.empty()) return;
    // Once in each check interval: in the step that reaches one of its multiples.
    const double interval = mScene.lattice.handoffCheckIntervalS;
    const bool checkDue = std::floor((mState.timeS + dtS) / interval) > std::floor(mState.timeS / interval);
    const std::unordered_map<int64_t, size_t> indexOf = bodyIndexById();
    std::vector<std::vector<Body>> parts(mState.bodies.size());
    std::vector<DeformableBody> staying, leaving;
    for (DeformableBody& d : mState.deformable) {
        const size_t i = indexOf.at(d.bodyId);
        const double sinceBlastS = mState.timeS - d.lastLoadedS;
        const double toleranceJ =
            mScene.lattice.handoffEnergyFraction * elasticCapacityPerVoxelJ(mScene.materials[mState.bodies[i].materialIndex], d.lattice.voxelSizeM);
        const bool timeUp = sinceBlastS >= mScene.lattice.maxVibrationS;
        Departure out;
        if (sinceBlastS > 0.0 && (checkDue || timeUp)) {
            mState.stepStats.latticeParticleSteps += catchUpDeformable(d);
            followLattice(mState.bodies[i], d.lattice);
            out = leaveQuietPieces(mState.bodies[i], d.lattice, toleranceJ, timeUp);
        }
        std::vector<Body>& leftParts = out.handOff.parts;
        if (leftParts.empty() || (leftParts.size() == 1 && leftParts.front().motion.deformable)) {
            staying.push_back(std::move(d));  // nothing leaves yet
            continue;
        }
        mState.handOffs.push_back({mState.timeS, d.bodyId, int64_t(d.lattice.voxelParticleCount), out.handOff.brokenBonds,
                                   out.handOff.brokenAnchors, mState.timeS - d.enteredS, out.discardedEnergyJ, out.timedOut});
        mState.stepStats.brokenLinks += out.handOff.brokenLinks;
        if (leftParts.size() == 1) {
            leftParts.front().id = mState.bodies[i].id;
            leftParts.front().parentId = mState.bodies[i].parentId;
            mState.bodies[i] = std::move(leftParts.front());
            continue;
        }
        parts[i] = std::move(leftParts);
        leaving.push_back(std::move(d));
    }
    mState.deformable = std::move(staying);
    replaceWithParts(parts);
    continueVibratingParts(leaving);
}

void Simulation::continueVibratingParts(const std::vector<DeformableBody>& leaving)
{
    std::unordered_map<int64_t, const DeformableBody*> leftBy;
    for (const DeformableBody& d : leaving) leftBy[d.bodyId] = &d;
    for (const Body& body : mState.bodies) {
        if (!body.motion.deformable || !leftBy.count(body.parentId)) continue;
        mState.deformable.push_back(continueDeformable(body, *leftBy.at(body.parentId), mScene.materials[body.materialIndex], mScene.lattice,
                                                       latticeSupports()));
        mState.deformable.back().bodyId = body.id;
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
