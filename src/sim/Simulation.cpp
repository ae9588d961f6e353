#include <spall/sim/Simulation.h>

#include <spall/core/Error.h>
#include <spall/dynamics/Contacts.h>
#include <spall/dynamics/Integrate.h>
#include <spall/dynamics/Sleep.h>
#include <spall/loads/BlastLoads.h>
#include <spall/loads/Exposure.h>

#include <algorithm>
#include <cmath>
#include <optional>

namespace spall {

StepStats Simulation::takeStepStats()
{
    StepStats s = mState.stepStats;
    mState.stepStats = StepStats();
    mState.stepStats.minDtS = mScene.timeStep.maxTimeStepS;
    return s;
}

bool Simulation::advanceTo(double targetS, Interrupter* interrupter, const std::function<void()>& afterStep)
{
    mInterrupter = interrupter;
    const std::unique_ptr<Interrupter*, void (*)(Interrupter**)> forget(&mInterrupter, [](Interrupter** i) { *i = nullptr; });
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

    const BlastLoads blast(*mField, windows, mScene.loads, mStaticWorld);
    const std::vector<char> loaded = blast.loadedBodies(mState.bodies);
    wakeLoadedBodies(mState.bodies, loaded);
    mFaceForces.wanted.clear();
    for (const Body& body : mState.bodies) mFaceForces.wanted.push_back(body.motion.deformable);
    const std::vector<Wrench> blastWrenches = blast.stepWrenches(mState.bodies, loaded, mState.timeS, dt, &mFaceForces);
    integrateBodies(mState.bodies, blastWrenches, mScene.world, airOf(mScene.blast.atmosphere), mScene.timeStep.integrator, mState.timeS, dt);
    deformBodies(mFaceForces, windows, dt);

    ContactSet contacts = detectContacts(mState.bodies, mScene.world, mScene.collisions, mScene.sleep);
    enterOnImpact(contacts, dt);
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
        const LoadResult r = loadLinks(body, mScene.materials[body.materialIndex], *pressure, dt, mScene.fracture, mScene.seed);
        mState.stepStats.brokenLinks += r.brokenLinks;
        cracked[i] = r.brokenLinks > 0 || r.brokenAnchors > 0;
    }
    return cracked;
}

std::vector<BodyMomenta> Simulation::bodyMomenta() const
{
    std::vector<BodyMomenta> motions;
    motions.reserve(mState.bodies.size());
    for (const Body& b : mState.bodies) motions.push_back({kineticEnergyJ(b), linearMomentum(b), angularMomentumAboutOrigin(b)});
    const DeformablePhase& phase = mState.deformable;
    for (size_t k = 0; k < phase.lattices.size(); ++k) {
        const Lattice& lattice = phase.lattices[k].lattice;
        motions[phase.bodyIndex(k, mState.bodies)] = {lattice.kineticEnergyJ(), lattice.linearMomentum(), lattice.angularMomentumAboutOrigin()};
    }
    return motions;
}

std::vector<Body> Simulation::showPieces() { return mState.deformable.showPieces(mState.bodies, mState.nextId); }

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
        if (cracked[i]) {
            parts[i] = splitBody(mState.bodies[i]);
            for (Body& part : parts[i]) part.id = kNoBodyId;
        }
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
            if (part.id == kNoBodyId) part.id = mState.nextId++;
            event.childIds.push_back(part.id);
            next.push_back(std::move(part));
        }
        mState.events.push_back(std::move(event));
    }
    mState.bodies = std::move(next);
    mState.deformable.reindex(mState.bodies);
}

void Simulation::enterDeformablePhase(const std::vector<OpenWindow>& windows)
{
    if (mScene.fracture.algorithm != FractureAlgorithm::Lattice || windows.empty()) return;
    std::vector<char> reached(mState.bodies.size());
    for (size_t i = 0; i < reached.size(); ++i) reached[i] = bodyInWindows(mState.bodies[i], *mField, windows);
    mState.deformable.enter(mState.bodies, reached, mScene.materials, mScene.lattice, mStaticWorld, mScene.seed, mState.timeS);
}

namespace {

/// A material's impedance ρ c_p: the stress a flat impact at 1 m/s puts in it against a rigid
/// face (Kolsky, Stress Waves in Solids, 1963, ch. 4) (unit: Pa s/m).
double impedancePaSPerM(const Material& material) { return material.densityKgM3 * pWaveSpeedMS(material); }

/// A compliant ground stresses a body that strikes it at v as a rigid one at v Z₂ / (Z₁ + Z₂),
/// Z = ρ c_p the body's and the ground's impedances (Kolsky 1963, ch. 4): that fraction (1 on a
/// rigid ground).
double groundShareOfImpact(const Material& material, const GroundPlane& ground)
{
    const double groundImpedance = groundImpedancePaSPerM(ground);
    return std::isinf(groundImpedance) ? 1.0 : groundImpedance / (impedancePaSPerM(material) + groundImpedance);
}

/// Whether a body can be a lattice: it has links to break, or anchors (DeformablePhase::enter).
bool canDeform(const Body& body) { return body.motion.deformable || body.linkCount > 0 || body.anchored; }

/// A body about to strike the ground or a collider as a lattice starts touching it, not sunk
/// into it: a rigid step carries it up to its travel in a step deeper, and the lattice's elastic
/// contact would give the sunk particles' overlap back as energy the impact never had. It moves
/// out along each contact's normal by what is left of its depth, deepest first.
void leaveStaticsBeforeEntering(Body& body, const std::vector<StaticContact>& statics)
{
    std::vector<const StaticContact*> deepestFirst;
    for (const StaticContact& c : statics) deepestFirst.push_back(&c);
    std::sort(deepestFirst.begin(), deepestFirst.end(), [](const StaticContact* x, const StaticContact* y) { return x->depth > y->depth; });
    Eigen::Vector3d movedM = Eigen::Vector3d::Zero();
    for (const StaticContact* c : deepestFirst) movedM += std::max(0.0, c->depth - c->normal.dot(movedM)) * c->normal;
    body.motion.positionM += movedM;
}

}  // namespace

bool Simulation::strikesHardEnoughToCrack(double closingMS, const Body& body, double share, double dtS) const
{
    const double speedMS = closingMS * share;
    // A contact that rests (impactSpeedMS) strikes nothing, however weak the material; one no
    // faster than an impact the body took as a lattice grows no damage, a lattice's included
    // (else a lattice that a rigid piece rubs against pulls it in at every touch).
    return speedMS > std::max(impactSpeedMS(mScene.world, dtS), body.motion.survivedImpactMS) &&
           speedMS >= crackingImpactSpeedMS(body, mScene.materials[body.materialIndex], mScene.lattice.particleVoxels);
}

bool Simulation::crackingImpactBetween(const ContactManifold& m, double dtS)
{
    Body& a = mState.bodies[size_t(m.a)];
    Body& b = mState.bodies[size_t(m.b)];
    if (!canDeform(a) || !canDeform(b) || (a.motion.deformable && b.motion.deformable)) return false;
    // Each side takes v Z_other / (Z_a + Z_b) of the closing speed v (Kolsky 1963, ch. 4).
    const double za = impedancePaSPerM(mScene.materials[a.materialIndex]), zb = impedancePaSPerM(mScene.materials[b.materialIndex]);
    const double closingMS = fastestClosingSpeedMS(mState.bodies, m), shareA = zb / (za + zb), shareB = za / (za + zb);
    if (!strikesHardEnoughToCrack(closingMS, a, shareA, dtS) && !strikesHardEnoughToCrack(closingMS, b, shareB, dtS)) return false;
    for (const auto& [body, share] : {std::make_pair(&a, shareA), std::make_pair(&b, shareB)})
        body->motion.survivedImpactMS = std::max(body->motion.survivedImpactMS, closingMS * share);
    return true;
}

void Simulation::separateBeforeEntering(const ContactManifold& m)
{
    Body& a = mState.bodies[size_t(m.a)];
    Body& b = mState.bodies[size_t(m.b)];
    const auto inverseMass = [](const Body& body) { return body.anchored || body.motion.deformable ? 0.0 : 1.0 / body.mass.massKg; };
    // Pieces that left the phase overlapping each other keep that overlap excused (the rigid
    // solver's slack, BodyMotion::overlapSlackM, the smaller body's): their voxels overlapped so
    // far where their particles only touched.
    const double excusedM = std::min(std::max(a.motion.overlapSlackM, 0.0), std::max(b.motion.overlapSlackM, 0.0));
    const double wa = inverseMass(a), wb = inverseMass(b), depthM = std::max(0.0, m.maxDepthM - excusedM);
    if (wa + wb == 0.0 || depthM == 0.0) return;
    // The normal points from b to a.
    a.motion.positionM += (depthM * wa / (wa + wb)) * m.normal;
    b.motion.positionM -= (depthM * wb / (wa + wb)) * m.normal;
}

void Simulation::enterOnImpact(ContactSet& contacts, double dtS)
{
    if (mScene.fracture.algorithm != FractureAlgorithm::Lattice || !mScene.lattice.impactFracture) return;
    std::vector<char> striking(mState.bodies.size(), 0), wasLattice(mState.bodies.size(), 0);
    std::vector<double> closingAtEntryMS(mState.bodies.size(), 0.0);
    for (size_t i = 0; i < mState.bodies.size(); ++i) wasLattice[i] = mState.bodies[i].motion.deformable;
    for (size_t i = 0; i < mState.bodies.size(); ++i) {
        Body& body = mState.bodies[i];
        if (body.motion.deformable || body.linkCount == 0 || contacts.statics[i].empty()) continue;
        const double closingMS =
            fastestClosingSpeedMS(body, contacts.statics[i], groundShareOfImpact(mScene.materials[body.materialIndex], mScene.world.ground));
        striking[i] = strikesHardEnoughToCrack(closingMS, body, 1.0, dtS);
        if (!striking[i]) continue;
        closingAtEntryMS[i] = closingMS;
        body.motion.survivedImpactMS = closingMS;
        leaveStaticsBeforeEntering(body, contacts.statics[i]);
        // Its particles take the impact: the solver must not stop it as a rigid body first.
        contacts.staticContacts -= int64_t(contacts.statics[i].size());
        contacts.solverContacts -= int64_t(contacts.statics[i].size());
        contacts.statics[i].clear();
    }
    // Two bodies striking each other both become lattices, which meet particle to particle
    // (LatticePairContact.h): the solver leaves them to it.
    std::vector<ContactManifold> kept;
    for (ContactManifold& m : contacts.manifolds) {
        if (!crackingImpactBetween(m, dtS)) {
            kept.push_back(std::move(m));
            continue;
        }
        const double closingMS = fastestClosingSpeedMS(mState.bodies, m);
        for (const int i : {m.a, m.b}) {
            striking[size_t(i)] = 1;
            closingAtEntryMS[size_t(i)] = std::max(closingAtEntryMS[size_t(i)], closingMS);
        }
        separateBeforeEntering(m);
        contacts.solverContacts -= int64_t(m.points.size());
    }
    contacts.manifolds = std::move(kept);
    // The bodies are where the step's end puts them.
    mState.deformable.enter(mState.bodies, striking, mScene.materials, mScene.lattice, mStaticWorld, mScene.seed, mState.timeS + dtS);
    holdForImpacts(striking, wasLattice, closingAtEntryMS, dtS);
}

void Simulation::holdForImpacts(const std::vector<char>& struck, const std::vector<char>& wasLattice, const std::vector<double>& closingAtEntryMS,
                                double dtS)
{
    // The impact loads it for as long as a bar striking a rigid wall stays in contact, 2 L / c
    // (Kolsky 1963, ch. 4), L its largest extent, twice its bounding radius: no hand-off before
    // the impact has played out, counted, for a body that enters for it, from when its particles
    // meet what it struck (DeformablePhase::awaitImpacts). They may lag its rigid voxels' contact
    // by up to (√3 − 1 + 0.1) voxels: turned cubes whose corners touch, found a tenth of a voxel
    // early, have their centres up to √3 voxels apart, where the lattices' particles touch at
    // one (against the ground (√3 − 1) / 2 + 0.1 = 0.47). At the entry's closing speed that gap
    // closes in the time it waits at most.
    constexpr double kParticleContactLagVoxels = 0.832;
    for (size_t k = 0; k < mState.deformable.lattices.size(); ++k) {
        const size_t i = mState.deformable.bodyIndex(k, mState.bodies);
        const Body& body = mState.bodies[i];
        if (!struck[i]) continue;
        DeformableBody& d = mState.deformable.lattices[k];
        const double enteredS = mState.timeS + dtS, impactS = 4.0 * body.boundingRadiusM / pWaveSpeedMS(mScene.materials[body.materialIndex]);
        d.lastLoadedS = std::max(d.lastLoadedS, enteredS + impactS);
        if (wasLattice[i]) continue;  // its particles are where it is
        d.awaitedImpactS = impactS;
        d.coasting = !d.lattice.pressedOnASurface();  // built pressing something: no wait to coast through
        d.awaitImpactUntilS = enteredS + kParticleContactLagVoxels * body.voxelSizeM / std::max(closingAtEntryMS[i], impactSpeedMS(mScene.world, dtS));
    }
}

void Simulation::deformBodies(const FaceForces& faces, const std::vector<OpenWindow>& windows, double dtS)
{
    if (mState.deformable.empty()) return;
    const auto reached = [&](const Body& body) { return bodyInWindows(body, *mField, windows); };
    const auto abandon = [this] { return mInterrupter && mInterrupter->mustAbandonStep(); };
    mState.stepStats.latticeParticleSteps +=
        mState.deformable.deform(mState.bodies, faces.forceN, mScene.world.gravityMS2, reached, mState.timeS, dtS, abandon);
}

void Simulation::solveContactsWithLattices(const ContactSet& contacts, double dtS)
{
    DeformablePhase& phase = mState.deformable;
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> before;
    for (size_t k = 0; k < phase.lattices.size(); ++k) {
        const Body& body = mState.bodies[phase.bodyIndex(k, mState.bodies)];
        before.emplace_back(linearMomentum(body), angularMomentumAboutOrigin(body));
    }
    solveContacts(mState.bodies, contacts, mScene.world, mScene.collisions, dtS, mState.contactCache);
    for (size_t k = 0; k < phase.lattices.size(); ++k) {
        Body& body = mState.bodies[phase.bodyIndex(k, mState.bodies)];
        if (!takesContactImpulses(body)) continue;
        const Eigen::Vector3d linear = linearMomentum(body) - before[k].first, angular = angularMomentumAboutOrigin(body) - before[k].second;
        if (linear.isZero(0.0) && angular.isZero(0.0)) continue;  // no contact moved it
        addRigidMomentum(phase.lattices[k].lattice, linear, angular);
        followLattice(body, phase.lattices[k].lattice);
    }
}

void Simulation::handOffQuietBodies(double dtS)
{
    if (mState.deformable.empty()) return;
    PhaseDepartures out = mState.deformable.leaveQuietPieces(mState.bodies, mScene.materials, mScene.lattice, mState.timeS, dtS, mState.handOffs);
    mState.stepStats.latticeParticleSteps += out.particleSteps;
    mState.stepStats.brokenLinks += out.brokenLinks;
    if (out.leaving.empty()) return;  // no body left in parts: the bodies are where they were
    replaceWithParts(out.parts);
    mState.deformable.continueVibratingParts(mState.bodies, out.leaving, mScene.materials, mScene.lattice, mStaticWorld, mScene.seed);
}

}  // namespace spall
