// The deformable phase as a stage (issue 17): the bodies that are lattices now, each with its
// body's place among the simulation's bodies, and the parts of a step that concern them — enter,
// deform, leave — which Simulation::step calls in order. What it holds is what a checkpoint saves.
#pragma once

#include <spall/fracture/Material.h>
#include <spall/lattice/Deformable.h>
#include <spall/lattice/LatticePairContact.h>
#include <spall/lattice/Settings.h>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

namespace spall {

/// A body leaving the deformable phase (fracture.algorithm "lattice").
struct HandOffRecord {
    double timeS = 0;  ///< (unit: s)
    int64_t bodyId = 0;
    int64_t particles = 0;
    int64_t brokenBonds = 0;
    int64_t brokenAnchors = 0;
    double deformableS = 0;       ///< how long it was deformable (unit: s)
    double discardedEnergyJ = 0;  ///< its vibration then, which the rigid parts do not carry (unit: J)
    bool timedOut = false;        ///< left at lattice.max_vibration_s, not because it was quiet
};

/// What a look for quiet pieces leaves to the caller (DeformablePhase::leaveQuietPieces).
struct PhaseDepartures {
    /// Per body (its index before the look), the parts that replace it; empty: it stays whole.
    std::vector<std::vector<Body>> parts;
    /// The lattices of bodies that left in several parts: parts still vibrating carry on from
    /// them (DeformablePhase::continueVibratingParts).
    std::vector<DeformableBody> leaving;
    int64_t brokenLinks = 0;
    int64_t particleSteps = 0;  ///< the lattice steps taken to catch up before looking
};

/// Whether the blast reaches a body during the step (an open window meets it).
using ReachedByBlast = std::function<bool(const Body&)>;

/// What a pair of lattices' contact excuses of their overlap (LatticePairContact::overlapExcuseM).
struct PairOverlapExcuse {
    int64_t bodyIdA = 0, bodyIdB = 0;
    double excuseM = 0.0;  ///< (unit: m)
};

class DeformablePhase {
public:
    /// The bodies in the phase, in the order they entered.
    std::vector<DeformableBody> lattices;
    /// Per pair of lattices that may touch, by their bodies' ids (the smaller first, sorted), the
    /// overlap their contact excuses: state a checkpoint keeps, where the contacts themselves are
    /// a cache. A pair without one has its overlap excused when its contact is made: the two
    /// overlap then only by what the rigid phase left them (LatticePairContact).
    std::vector<PairOverlapExcuse> pairOverlapExcuses;

    bool empty() const { return lattices.empty(); }
    /// Lattice k's body among `bodies`, checked against its id.
    size_t bodyIndex(size_t k, const std::vector<Body>& bodies) const;
    /// Finds each lattice's body again after the bodies were replaced or restored: between
    /// those, a lattice knows its body's place without a lookup.
    void reindex(const std::vector<Body>& bodies);

    /// The most particle-steps its lattices can still take: each steps at most until
    /// `maxVibrationS` after the blast last loaded it, or after the impact it awaits, taken at
    /// the end of its wait (to within the rigid step that ends it); 0 when the phase is empty.
    /// While the blast still acts it moves that time on: the bound leaves out what remains of the
    /// loading, a few milliseconds against the tenth of a second of `maxVibrationS`.
    int64_t particleStepsLeftAtMost(double timeS, double maxVibrationS) const;
    /// Bodies marked `entering` (per body: the blast reaches them, or they strike something hard
    /// enough to crack) that have links or anchors become lattices.
    void enter(std::vector<Body>& bodies, const std::vector<char>& entering, const std::vector<Material>& materials,
               const LatticeSettings& settings, const StaticWorld& supports, uint64_t seed, double timeS);
    /// Each lattice through a step of dtS under its faces' forces (per body, FaceForces::forceN)
    /// and gravity, lattices that may touch stepped together so that their particles meet
    /// (LatticePairContact.h); each body follows its lattice. Returns the particle-steps taken. `abandon` is asked
    /// before each lattice step (advanceDeformable).
    int64_t deform(std::vector<Body>& bodies, const std::vector<std::vector<Eigen::Vector3d>>& faceForcesN, const Eigen::Vector3d& gravityMS2,
                   const ReachedByBlast& reached, double timeS, double dtS, const std::function<bool()>& abandon = {});
    /// Bodies the blast has passed, looked at once per lattice.handoff_check_interval_s (in the
    /// step of length dtS that reaches a multiple of it) or when their time is up: their quiet
    /// pieces leave as rigid bodies (leaveQuietPieces, Deformable.h). A body that leaves whole is
    /// replaced in `bodies` at once, in its place; one that leaves in parts is left to the
    /// caller, which replaces it with `parts`, reindexes, then calls continueVibratingParts.
    /// A part has the id it was shown with (showPieces), or none yet (kNoBodyId).
    PhaseDepartures leaveQuietPieces(std::vector<Body>& bodies, const std::vector<Material>& materials, const LatticeSettings& settings,
                                     double timeS, double dtS, std::vector<HandOffRecord>& records);
    /// The bodies as a frame shows them: a body whose lattice has come apart (some bond broken at
    /// hand-off, Lattice::brokenAtHandOff) as the parts a hand-off now would give, at their
    /// particles' best-fit poses and rigid motion (handOff), after it in `bodies`' order. A
    /// part keeps the id it was first shown with, which a hand-off gives it too
    /// (leaveQuietPieces), so its path through the frames runs on; new ids come from `nextId`.
    std::vector<Body> showPieces(const std::vector<Body>& bodies, int64_t& nextId);
    /// Parts marked deformable of bodies that left (`leaving`) carry on in the phase, with
    /// lattices that take their state from their whole's.
    void continueVibratingParts(const std::vector<Body>& bodies, const std::vector<DeformableBody>& leaving,
                                const std::vector<Material>& materials, const LatticeSettings& settings, const StaticWorld& supports,
                                uint64_t seed);

private:
    /// Lattices that may touch one another through a step, directly or through others: stepped
    /// together (advanceTogether).
    struct TouchingGroup {
        std::vector<size_t> lattices;                    ///< indices into `lattices`, ascending
        std::vector<std::pair<size_t, size_t>> touching;  ///< pairs that may touch, as places in the group
    };
    /// The lattices in groups that may touch through a step of dtS (one each when none does),
    /// in the order of their first lattice.
    std::vector<TouchingGroup> touchingGroups(double dtS) const;
    /// A lattice that entered for an impact stays in the phase, as if loaded, until its
    /// particles meet something (the ground, a collider, another lattice) or its wait is over;
    /// the impact then loads it for its awaitedImpactS (none when the wait is over). Its rigid
    /// body met what it struck as turned cubes, found a tenth of a voxel early; its particles
    /// touch as unturned cubes on a surface and as spheres one edge across between lattices, so
    /// they may still be up to 0.47 of a voxel from the ground and 0.83 from another lattice
    /// (Simulation::enterOnImpact), and a lattice that left before touching would leave its
    /// body still falling onto what it struck, to enter again. Touching anything counts: a body
    /// resting on the ground that another strikes is released at once.
    void awaitImpacts(double timeS, double dtS);
    /// Per lattice, its body's index (reindex).
    std::vector<size_t> mBodyIndex;
    /// The contacts of the pairs of lattices that may touch, by their bodies' ids, kept while
    /// the pair may touch so that their lists are not made again every rigid step; all dropped
    /// when a lattice leaves (a part may keep its whole's id). A cache: the forces do not depend
    /// on when a list was made (LatticePairContact::addForces), and what else a contact keeps
    /// is in pairOverlapExcuses, so a checkpoint leaves it out.
    std::map<std::pair<int64_t, int64_t>, LatticePairContact> mPairContacts;
    /// The contacts of a group's touching pairs: made when new, with the excuse the pair had in
    /// pairOverlapExcuses, else with their overlap then excused (LatticePairContact); `used`
    /// collects their keys.
    std::vector<LatticePairContact*> contactsOf(const TouchingGroup& group, std::vector<std::pair<int64_t, int64_t>>& used);
    /// The excuse kept for a pair of bodies, if any.
    std::optional<double> storedOverlapExcuseM(int64_t bodyIdA, int64_t bodyIdB) const;
    /// Bodies that left the phase whole keep no excuse.
    void forgetOverlapExcusesOf(const std::vector<int64_t>& bodyIds);
    /// A whole's excuses pass to each of its parts that carry on as lattices (by whole's id, the
    /// parts' ids, none if all its parts left); the parts among themselves excuse nothing.
    void passOverlapExcusesToParts(const std::unordered_map<int64_t, std::vector<int64_t>>& continuingPartsOf);
};

}  // namespace spall
