// Contact between two lattices of the deformable phase (issue 48, item 2): bodies that strike
// each other meet particle to particle, so a brick dents and cracks a pane where it touches it,
// not the pane as a whole. Lattices that may touch are stepped together (advanceTogether,
// below), these forces added between the halves of each step (Lattice::moveAndMeasure,
// finishStep).
#pragma once

#include <spall/lattice/Deformable.h>
#include <spall/lattice/Lattice.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace spall {

/// The fastest a particle moves (unit: m/s).
double fastestParticleSpeedMS(const Lattice& lattice);

/// At least the farthest a particle of `lattice` moved in the step of dtS it has just drifted
/// (Lattice::moveAndMeasure: dt times its velocity then), rounding included (unit: m).
double stepTravelBoundM(const Lattice& lattice, double dtS);

/// The box that holds a lattice's particles' centres.
Eigen::AlignedBox3d particleBox(const Lattice& lattice);

/// A normal spring between a voxel's particle of each lattice while their centres are closer
/// than the sum of their half edges, along the line of centres, never pulling: each side a half
/// edge of its own material (Lattice::surfaceStiffnessNPerM twice) in series, as the ground's
/// contact takes a half voxel each side, but never stiffer than the softer side's bond (the
/// ground's spring, which the stable step allows; for very different materials the interface is
/// then up to half as stiff as the series). The waves behind it, not the spring, set the stress:
/// two bodies of one material closing flat at v press each other with ρ c v / 2 (Kolsky, Stress
/// Waves in Solids, 1963, ch. 4). Forces are equal and opposite: momentum is kept exactly, and
/// the spring stores and gives back what it takes.
///
/// A contact may excuse an overlap: its particles push only once closer than that, and the
/// excuse shrinks as the overlap does, never growing again (as the rigid solver excuses the
/// overlap pieces leave the phase with, BodyMotion::overlapSlackM). A body that was rigid a
/// moment ago overlaps its neighbours by what the rigid phase let it (a 1 ms step at 5 m/s is
/// 5 mm), and a spring as stiff as a bond turns that into energy the pieces never had: 1.3 mm
/// threw the default wall's bricks at hundreds of m/s. The deformable phase excuses the overlap
/// every new contact finds, unless the pair has an excuse kept (DeformablePhase::contactsOf).
class LatticePairContact {
public:
    /// `overlapExcuseM`: the excuse the pair's contact had before (a checkpoint, a contact made
    /// again); none: the deepest overlap now.
    LatticePairContact(const Lattice& a, const Lattice& b, std::optional<double> overlapExcuseM = std::nullopt);
    /// Adds the contact forces at the particles' present places to a's and b's bondForceN.
    /// `travelAM`, `travelBM`: at least the farthest a particle of each moved since the last
    /// call (stepTravelBoundM; infinity when not known).
    void addForces(Lattice& a, Lattice& b, double travelAM, double travelBM);
    double stiffnessNPerM() const { return mStiffnessNPerM; }
    /// How much closer than touching the particles are before they push (unit: m).
    double overlapExcuseM() const { return mOverlapExcuseM; }
    /// Whether its particles have pushed each other since it was made.
    bool pushed() const { return mPushed; }

private:
    double mTouchM, mSkinM, mStiffnessNPerM;
    double mOverlapExcuseM = 0.0;
    bool mPushed = false;
    /// Pairs (a's particle, b's) whose centres were within touching plus the skin when last
    /// listed, sorted: a Verlet list, listed again once a particle of either has moved half the
    /// skin since.
    std::vector<std::pair<uint32_t, uint32_t>> mCandidates;
    std::vector<Eigen::Vector3d> mListedAM, mListedBM;
    /// At least the farthest a particle of a and of b has moved since the list was made: the
    /// particles are measured only once either passes half the skin, and the list is made
    /// again exactly when it would be if they were measured every step.
    double mMovedBoundAM = std::numeric_limits<double>::infinity(), mMovedBoundBM = std::numeric_limits<double>::infinity();
    bool movedHalfTheSkin(const Lattice& a, const Lattice& b, double travelAM, double travelBM);
    /// The most a listed pair's particles overlap now (0: none does) (unit: m).
    double deepestOverlapM(const Lattice& a, const Lattice& b) const;
    void listCandidates(const Lattice& a, const Lattice& b);
};

/// Lattices that may touch (`touching`: pairs of indices into `group`, each with its contact in
/// `contacts`, made for that pair and kept from step to step for its list) through a rigid step
/// of dtS, stepped together so that their particles meet: each first steps what it had gathered
/// (catchUpDeformable) under the forces it gathered them with, then all take the same whole
/// number of equal steps, none longer than the shortest of their stable steps, under the
/// external forces setExternalForces left, each pair's contact forces added between the halves
/// of each step. None is left with time gathered. Returns the particle-steps taken; asks
/// `abandon` before each step (advanceDeformable).
int64_t advanceTogether(const std::vector<DeformableBody*>& group, const std::vector<std::pair<size_t, size_t>>& touching,
                        const std::vector<LatticePairContact*>& contacts, double dtS, const std::function<bool()>& abandon = {});

}  // namespace spall
