#include <spall/lattice/DeformablePhase.h>

#include <spall/core/DisjointSets.h>
#include <spall/core/Error.h>
#include <spall/lattice/LatticePairContact.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>

namespace spall {

size_t DeformablePhase::bodyIndex(size_t k, const std::vector<Body>& bodies) const
{
    SPALL_CHECK(k < mBodyIndex.size() && mBodyIndex[k] < bodies.size() && bodies[mBodyIndex[k]].id == lattices[k].bodyId);
    return mBodyIndex[k];
}

void DeformablePhase::reindex(const std::vector<Body>& bodies)
{
    mBodyIndex.clear();
    if (lattices.empty()) return;
    std::unordered_map<int64_t, size_t> indexOf;
    for (size_t i = 0; i < bodies.size(); ++i) indexOf[bodies[i].id] = i;
    for (const DeformableBody& d : lattices) {
        const auto found = indexOf.find(d.bodyId);
        if (found == indexOf.end()) throw InputError("saved state: deformable body " + std::to_string(d.bodyId) + " is not among the bodies");
        mBodyIndex.push_back(found->second);
    }
}

int64_t DeformablePhase::particleStepsLeftAtMost(double timeS, double maxVibrationS) const
{
    int64_t steps = 0;
    for (const DeformableBody& d : lattices) {
        // A lattice awaiting its impact may wait until its wait ends and then take the impact.
        const double loadedUntilS = d.awaitedImpactS > 0.0 ? std::max(d.lastLoadedS, d.awaitImpactUntilS + d.awaitedImpactS) : d.lastLoadedS;
        const double leftS = std::max(0.0, loadedUntilS + maxVibrationS - timeS) + d.pendingS;
        steps += static_cast<int64_t>(std::ceil(leftS / d.lattice.stableTimeStepS())) * static_cast<int64_t>(d.lattice.particleCount());
    }
    return steps;
}

void DeformablePhase::enter(std::vector<Body>& bodies, const std::vector<char>& entering, const std::vector<Material>& materials,
                            const LatticeSettings& settings, const StaticWorld& supports, uint64_t seed, double timeS)
{
    for (size_t i = 0; i < bodies.size(); ++i) {
        Body& body = bodies[i];
        if (body.motion.deformable || (body.linkCount == 0 && !body.anchored) || !entering[i]) continue;
        lattices.push_back(enterDeformablePhase(body, materials[body.materialIndex], settings, supports, seed, timeS));
        mBodyIndex.push_back(i);
        body.motion.deformable = true;
        body.motion.asleep = false;
        body.motion.restTimeS = 0.0;
    }
}

namespace {

/// A pair of bodies' ids in the order their excuse is kept by (PairOverlapExcuse).
std::pair<int64_t, int64_t> orderedPair(int64_t idA, int64_t idB) { return std::minmax(idA, idB); }

bool byPair(const PairOverlapExcuse& a, const PairOverlapExcuse& b)
{
    return std::make_pair(a.bodyIdA, a.bodyIdB) < std::make_pair(b.bodyIdA, b.bodyIdB);
}

}  // namespace

std::vector<DeformablePhase::TouchingGroup> DeformablePhase::touchingGroups(double dtS) const
{
    // A lattice alone is its own group: no pass over its particles for boxes and speeds.
    if (lattices.size() == 1) return {TouchingGroup{{0}, {}}};
    // Two lattices may meet within the step if their boxes come within touching of each other,
    // each moving at its fastest particle's speed over the step and the time it has gathered,
    // with a skin of an edge: a third lattice striking one within the step speeds it up.
    std::vector<double> fastestMS;
    std::vector<Eigen::AlignedBox3d> boxes;
    for (const DeformableBody& d : lattices) {
        fastestMS.push_back(fastestParticleSpeedMS(d.lattice));
        boxes.push_back(particleBox(d.lattice));
    }
    DisjointSets sets(lattices.size());
    std::vector<std::pair<size_t, size_t>> touching;
    for (size_t k = 0; k < lattices.size(); ++k)
        for (size_t l = k + 1; l < lattices.size(); ++l) {
            const double hk = lattices[k].lattice.model().spacingM, hl = lattices[l].lattice.model().spacingM;
            const double reachM = 0.5 * (hk + hl) + std::max(hk, hl) + fastestMS[k] * (dtS + lattices[k].pendingS) +
                                  fastestMS[l] * (dtS + lattices[l].pendingS);
            if (boxes[k].exteriorDistance(boxes[l]) >= reachM) continue;
            touching.emplace_back(k, l);
            sets.join(uint32_t(k), uint32_t(l));
        }
    std::vector<TouchingGroup> groups;
    std::vector<size_t> groupOfRoot(lattices.size(), SIZE_MAX), placeInGroup(lattices.size());
    for (size_t k = 0; k < lattices.size(); ++k) {
        size_t& g = groupOfRoot[sets.root(uint32_t(k))];
        if (g == SIZE_MAX) {
            g = groups.size();
            groups.emplace_back();
        }
        placeInGroup[k] = groups[g].lattices.size();
        groups[g].lattices.push_back(k);
    }
    for (const auto& [k, l] : touching) groups[groupOfRoot[sets.root(uint32_t(k))]].touching.emplace_back(placeInGroup[k], placeInGroup[l]);
    return groups;
}

int64_t DeformablePhase::deform(std::vector<Body>& bodies, const std::vector<std::vector<Eigen::Vector3d>>& faceForcesN,
                                const Eigen::Vector3d& gravityMS2, const ReachedByBlast& reached, double timeS, double dtS,
                                const std::function<bool()>& abandon)
{
    for (size_t k = 0; k < lattices.size(); ++k) {
        const size_t i = bodyIndex(k, bodies);
        setExternalForces(lattices[k], bodies[i], faceForcesN[i], gravityMS2);
        // Loaded unevenly (by the blast), it strains: it steps as a lattice from now on.
        if (lattices[k].coasting && !lattices[k].lattice.movesAsARigidBody()) lattices[k].coasting = false;
    }
    int64_t particleSteps = 0;
    std::vector<std::pair<int64_t, int64_t>> used;
    for (const TouchingGroup& group : touchingGroups(dtS)) {
        if (group.lattices.size() == 1) {
            particleSteps += advanceDeformable(lattices[group.lattices.front()], dtS, abandon);
            continue;
        }
        std::vector<DeformableBody*> members;
        for (const size_t k : group.lattices) members.push_back(&lattices[k]);
        particleSteps += advanceTogether(members, group.touching, contactsOf(group, used), dtS, abandon);
    }
    std::sort(used.begin(), used.end());
    for (auto it = mPairContacts.begin(); it != mPairContacts.end();)
        it = std::binary_search(used.begin(), used.end(), it->first) ? std::next(it) : mPairContacts.erase(it);
    pairOverlapExcuses.clear();
    for (const auto& [key, contact] : mPairContacts) {
        const auto [idA, idB] = orderedPair(key.first, key.second);
        pairOverlapExcuses.push_back({idA, idB, contact.overlapExcuseM()});
    }
    std::sort(pairOverlapExcuses.begin(), pairOverlapExcuses.end(), byPair);
    awaitImpacts(timeS, dtS);
    for (size_t k = 0; k < lattices.size(); ++k) {
        Body& body = bodies[bodyIndex(k, bodies)];
        followLattice(body, lattices[k].lattice);
        if (reached(body)) lattices[k].lastLoadedS = std::max(lattices[k].lastLoadedS, timeS + dtS);
    }
    return particleSteps;
}

void DeformablePhase::awaitImpacts(double timeS, double dtS)
{
    std::vector<int64_t> pushedIds;
    for (const auto& [ids, contact] : mPairContacts)
        if (contact.pushed()) pushedIds.insert(pushedIds.end(), {ids.first, ids.second});
    std::sort(pushedIds.begin(), pushedIds.end());
    const double nowS = timeS + dtS;
    for (DeformableBody& d : lattices) {
        if (d.awaitedImpactS == 0.0) continue;
        if (d.lattice.pressedOnASurface() || std::binary_search(pushedIds.begin(), pushedIds.end(), d.bodyId)) {
            d.lastLoadedS = std::max(d.lastLoadedS, nowS + d.awaitedImpactS);
            d.awaitedImpactS = 0.0;
        } else if (nowS >= d.awaitImpactUntilS) {
            d.awaitedImpactS = 0.0;  // it missed: what it struck as a rigid body its particles never reached
        } else {
            d.lastLoadedS = std::max(d.lastLoadedS, nowS);
        }
        if (d.awaitedImpactS == 0.0) d.coasting = false;  // a lattice coasts only while it waits
    }
}

std::vector<LatticePairContact*> DeformablePhase::contactsOf(const TouchingGroup& group, std::vector<std::pair<int64_t, int64_t>>& used)
{
    std::vector<LatticePairContact*> contacts;
    for (const auto& [i, j] : group.touching) {
        const DeformableBody &a = lattices[group.lattices[i]], &b = lattices[group.lattices[j]];
        const auto key = std::make_pair(a.bodyId, b.bodyId);
        auto contact = mPairContacts.find(key);
        if (contact == mPairContacts.end()) contact = mPairContacts.try_emplace(key, a.lattice, b.lattice, storedOverlapExcuseM(a.bodyId, b.bodyId)).first;
        contacts.push_back(&contact->second);
        used.push_back(key);
    }
    return contacts;
}

std::optional<double> DeformablePhase::storedOverlapExcuseM(int64_t bodyIdA, int64_t bodyIdB) const
{
    const auto [idA, idB] = orderedPair(bodyIdA, bodyIdB);
    const PairOverlapExcuse wanted{idA, idB, 0.0};
    const auto found = std::lower_bound(pairOverlapExcuses.begin(), pairOverlapExcuses.end(), wanted, byPair);
    if (found == pairOverlapExcuses.end() || found->bodyIdA != idA || found->bodyIdB != idB) return std::nullopt;
    return found->excuseM;
}

PhaseDepartures DeformablePhase::leaveQuietPieces(std::vector<Body>& bodies, const std::vector<Material>& materials,
                                                  const LatticeSettings& settings, double timeS, double dtS, std::vector<HandOffRecord>& records)
{
    PhaseDepartures out;
    if (lattices.empty()) return out;
    // Once in each check interval: in the step that reaches one of its multiples.
    const double interval = settings.handoffCheckIntervalS;
    const bool checkDue = std::floor((timeS + dtS) / interval) > std::floor(timeS / interval);
    out.parts.resize(bodies.size());
    std::vector<DeformableBody> staying;
    std::vector<size_t> stayingBodyIndex;
    std::vector<int64_t> leftWhole;
    for (size_t k = 0; k < lattices.size(); ++k) {
        DeformableBody& d = lattices[k];
        const size_t i = bodyIndex(k, bodies);
        Body& body = bodies[i];
        const double sinceBlastS = timeS - d.lastLoadedS;
        const double toleranceJ = settings.handoffEnergyFraction * elasticCapacityPerVoxelJ(materials[body.materialIndex], d.lattice.model().spacingM);
        const bool timeUp = sinceBlastS >= settings.maxVibrationS;
        // While the blast acts, a piece that has come free may leave the whole (separateFreePieces).
        const bool look =
            sinceBlastS > 0.0 ? checkDue || timeUp : settings.separateDuringBlast && checkDue && hasFreePieceAtHandOff(d.lattice);
        Departure departure;
        if (look) {
            out.particleSteps += catchUpDeformable(d);
            followLattice(body, d.lattice);
            departure = sinceBlastS > 0.0 ? spall::leaveQuietPieces(body, d.lattice, toleranceJ, timeUp) : separateFreePieces(body, d.lattice);
        }
        std::vector<Body>& leftParts = departure.handOff.parts;
        if (leftParts.empty() || (leftParts.size() == 1 && leftParts.front().motion.deformable)) {
            staying.push_back(std::move(d));  // nothing leaves yet
            stayingBodyIndex.push_back(i);
            continue;
        }
        records.push_back({timeS, d.bodyId, int64_t(d.lattice.model().voxelParticleCount), departure.handOff.brokenBonds, departure.handOff.brokenAnchors,
                           timeS - d.enteredS, departure.discardedEnergyJ, departure.timedOut});
        out.brokenLinks += departure.handOff.brokenLinks;
        if (leftParts.size() == 1) {
            leftWhole.push_back(body.id);
            leftParts.front().id = body.id;
            leftParts.front().parentId = body.parentId;
            body = std::move(leftParts.front());
            continue;
        }
        nameParts(d, leftParts, nullptr);
        out.parts[i] = std::move(leftParts);
        out.leaving.push_back(std::move(d));
    }
    // A body that left whole was replaced in place: the bodies' places are as they were. One
    // that comes back later overlaps by what the rigid phase left it then.
    if (staying.size() != lattices.size()) mPairContacts.clear();
    forgetOverlapExcusesOf(leftWhole);
    lattices = std::move(staying);
    mBodyIndex = std::move(stayingBodyIndex);
    return out;
}

std::vector<Body> DeformablePhase::showPieces(const std::vector<Body>& bodies, int64_t& nextId)
{
    std::vector<std::vector<Body>> partsOf(bodies.size());
    for (size_t k = 0; k < lattices.size(); ++k) {
        DeformableBody& d = lattices[k];
        const size_t i = bodyIndex(k, bodies);
        if (!anyBondBrokenAtHandOff(d.lattice)) continue;
        std::vector<Body> parts = handOff(bodies[i], d.lattice).parts;
        if (parts.size() < 2) continue;
        nameParts(d, parts, &nextId);
        for (Body& part : parts) part.parentId = bodies[i].id;
        partsOf[i] = std::move(parts);
    }
    std::vector<Body> shown;
    shown.reserve(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
        if (partsOf[i].empty()) shown.push_back(bodies[i]);
        for (Body& part : partsOf[i]) shown.push_back(std::move(part));
    }
    return shown;
}

void DeformablePhase::continueVibratingParts(const std::vector<Body>& bodies, const std::vector<DeformableBody>& leaving,
                                             const std::vector<Material>& materials, const LatticeSettings& settings,
                                             const StaticWorld& supports, uint64_t seed)
{
    std::unordered_map<int64_t, const DeformableBody*> leftBy;
    for (const DeformableBody& d : leaving) leftBy[d.bodyId] = &d;
    std::unordered_map<int64_t, std::vector<int64_t>> continuingPartsOf;
    for (const DeformableBody& d : leaving) continuingPartsOf[d.bodyId];  // a whole without such parts leaves no excuse
    for (size_t i = 0; i < bodies.size(); ++i) {
        const Body& body = bodies[i];
        if (!body.motion.deformable || !leftBy.count(body.parentId)) continue;
        lattices.push_back(continueDeformable(body, *leftBy.at(body.parentId), materials[body.materialIndex], settings, supports, seed));
        lattices.back().bodyId = body.id;
        mBodyIndex.push_back(i);
        continuingPartsOf[body.parentId].push_back(body.id);
    }
    passOverlapExcusesToParts(continuingPartsOf);
}

void DeformablePhase::forgetOverlapExcusesOf(const std::vector<int64_t>& bodyIds)
{
    const auto among = [&](int64_t id) { return std::find(bodyIds.begin(), bodyIds.end(), id) != bodyIds.end(); };
    pairOverlapExcuses.erase(std::remove_if(pairOverlapExcuses.begin(), pairOverlapExcuses.end(),
                                            [&](const PairOverlapExcuse& e) { return among(e.bodyIdA) || among(e.bodyIdB); }),
                             pairOverlapExcuses.end());
}

void DeformablePhase::passOverlapExcusesToParts(const std::unordered_map<int64_t, std::vector<int64_t>>& continuingPartsOf)
{
    if (continuingPartsOf.empty()) return;
    const auto idsNow = [&](int64_t id) {
        const auto parts = continuingPartsOf.find(id);
        return parts == continuingPartsOf.end() ? std::vector<int64_t>{id} : parts->second;
    };
    std::vector<PairOverlapExcuse> passed;
    // A part takes its whole's excuse with each other lattice: the overlap was its whole's.
    for (const PairOverlapExcuse& e : pairOverlapExcuses)
        for (const int64_t idA : idsNow(e.bodyIdA))
            for (const int64_t idB : idsNow(e.bodyIdB)) {
                const auto [a, b] = orderedPair(idA, idB);
                passed.push_back({a, b, e.excuseM});
            }
    // Parts of one whole that overlap press on each other, as they did while bonded.
    for (const auto& [wholeId, parts] : continuingPartsOf)
        for (size_t p = 0; p < parts.size(); ++p)
            for (size_t q = p + 1; q < parts.size(); ++q) {
                const auto [a, b] = orderedPair(parts[p], parts[q]);
                passed.push_back({a, b, 0.0});
            }
    std::sort(passed.begin(), passed.end(), byPair);
    pairOverlapExcuses = std::move(passed);
}

}  // namespace spall
