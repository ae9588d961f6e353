// Broad phase (paper section 4.2, sped up): the pairs of bodies whose bounding spheres overlap,
// and which bodies could meet another within a reach.
#pragma once

#include <spall/voxel/Body.h>

#include <vector>

namespace spall {

/// Pair of body indices, a < b.
struct BodyPair {
    int a, b;
    bool operator<(const BodyPair& o) const { return a != o.a ? a < o.a : b < o.b; }
    bool operator==(const BodyPair& o) const { return a == o.a && b == o.b; }
};

/// True when a contact between the two bodies could change anything: at least one of them moves,
/// and they are not both lattices, which meet particle to particle (lattice/LatticePairContact.h).
bool pairCanInteract(const Body& a, const Body& b);

/// Pairs whose bounding spheres overlap (found with a hierarchical grid) and that can interact,
/// sorted.
std::vector<BodyPair> findCandidatePairs(const std::vector<Body>& bodies);

/// Per body, whether its bounding sphere grown by `reachM[i]` meets another's grown by theirs
/// (every body counts: anchored, asleep, in the deformable phase).
std::vector<char> withinReachOfAnotherBody(const std::vector<Body>& bodies, const std::vector<double>& reachM);

}  // namespace spall
