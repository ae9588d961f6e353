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
        const double leftS = std::max(0.0, d.lastLoadedS + maxVibrationS - timeS) + d.pendingS;
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

/// Whether a lattice entered the phase for the step from timeS of length dtS: the blast's entry
/// is at the step's start, an impact's at the end of the step before (which lands on a frame's
/// time, not always bit for bit the sum of the steps).
bool enteredJustBefore(const DeformableBody& d, double timeS, double dtS) { return d.enteredS >= timeS - 0.5 * dtS; }

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
        particleSteps += advanceTogether(members, group.touching, contactsOf(group, timeS, dtS, used), dtS, abandon);
    }
    std::sort(used.begin(), used.end());
    for (auto it = mPairContacts.begin(); it != mPairContacts.end();)
        it = std::binary_search(used.begin(), used.end(), it->first) ? std::next(it) : mPairContacts.erase(it);
    pairOverlapExcuses.clear();
    for (const auto& [key, contact] : mPairContacts) pairOverlapExcuses.push_back({key.first, key.second, contact.overlapExcuseM()});
    for (size_t k = 0; k < lattices.size(); ++k) {
        Body& body = bodies[bodyIndex(k, bodies)];
        followLattice(body, lattices[k].lattice);
        if (reached(body)) lattices[k].lastLoadedS = timeS + dtS;
    }
    return particleSteps;
}

std::vector<LatticePairContact*> DeformablePhase::contactsOf(const TouchingGroup& group, double timeS, double dtS,
                                                             std::vector<std::pair<int64_t, int64_t>>& used)
{
    std::vector<LatticePairContact*> contacts;
    for (const auto& [i, j] : group.touching) {
        const DeformableBody &a = lattices[group.lattices[i]], &b = lattices[group.lattices[j]];
        const auto key = std::make_pair(a.bodyId, b.bodyId);
        auto contact = mPairContacts.find(key);
        if (contact == mPairContacts.end()) {
            const auto had = std::lower_bound(pairOverlapExcuses.begin(), pairOverlapExcuses.end(), key, [](const PairOverlapExcuse& e, const auto& k) {
                return std::make_pair(e.bodyIdA, e.bodyIdB) < k;
            });
            // Only a body that has just been rigid overlaps by the rigid phase's leave; parts of
            // one lattice that overlap press on each other.
            std::optional<double> excuseM;
            if (had != pairOverlapExcuses.end() && had->bodyIdA == key.first && had->bodyIdB == key.second)
                excuseM = had->excuseM;
            else if (!enteredJustBefore(a, timeS, dtS) && !enteredJustBefore(b, timeS, dtS))
                excuseM = 0.0;
            contact = mPairContacts.try_emplace(key, a.lattice, b.lattice, excuseM).first;
        }
        contacts.push_back(&contact->second);
        used.push_back(key);
    }
    return contacts;
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
            leftParts.front().id = body.id;
            leftParts.front().parentId = body.parentId;
            body = std::move(leftParts.front());
            continue;
        }
        nameParts(d, leftParts, nullptr);
        out.parts[i] = std::move(leftParts);
        out.leaving.push_back(std::move(d));
    }
    // A body that left whole was replaced in place: the bodies' places are as they were.
    if (staying.size() != lattices.size()) mPairContacts.clear();
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
    for (size_t i = 0; i < bodies.size(); ++i) {
        const Body& body = bodies[i];
        if (!body.motion.deformable || !leftBy.count(body.parentId)) continue;
        lattices.push_back(continueDeformable(body, *leftBy.at(body.parentId), materials[body.materialIndex], settings, supports, seed));
        lattices.back().bodyId = body.id;
        mBodyIndex.push_back(i);
    }
}

}  // namespace spall
