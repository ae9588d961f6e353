// Diffraction: the wave that reaches a face in the shadow of an obstacle by bending over the
// obstacle's nearest edge. The face is loaded by that wave, weakened and travelling away from
// the edge, instead of by the direct wave (which the obstacle stops) — so a body behind a
// blast wall is pushed by the flow that wraps over the wall, as the CFD reference shows
// (shared/reference/blast-loads-cfd.md), and a fragment's rear is loaded from where the wave
// really comes.
#pragma once

#include <spall/blast/Blast.h>
#include <spall/world/StaticWorld.h>

namespace spall {

/// The shortest path from a source to a point round a box.
struct EdgePath {
    double lengthM = 0;                               ///< source to point along the path (unit: m)
    Eigen::Vector3d enterM = Eigen::Vector3d::Zero();  ///< where it meets the box (an edge)
    Eigen::Vector3d leaveM = Eigen::Vector3d::Zero();  ///< where it leaves the box (an edge)
};

/// The shortest path from `sourceM` to `pointM` around the box. Across the box axis that points
/// most nearly along the line of sight, the box is a plate through its middle; the path turns
/// at one of the plate's four edges where, unfolded about the edge's line, it is straight
/// (clamped to the edge, the length being convex along it). It then meets the box at that
/// edge's copy on the face toward the source and leaves it at the copy on the face toward the
/// point, crossing the box's thickness in between. Exact for a thin obstacle (a wall), and
/// within the box's thickness of the true path around a thick one. An edge lying on or under
/// the ground (both ends within `groundToleranceM` of it) is no way round; the foot of a
/// vertical edge is.
EdgePath shortestPathAround(const ObstacleBox& box, const Eigen::Vector3d& sourceM, const Eigen::Vector3d& pointM,
                            const StaticWorld& geometry, double groundToleranceM);

/// The diffracted wave at a point in shadow, as a fraction of the direct wave's strength there.
struct DiffractedWave {
    /// The free-field wave whose pressures the diffracted wave has: the path length stretched by
    /// the diffraction factor (unit: m).
    double equivalentDistanceM = 0;
    /// Unit direction in which the diffracted wave travels at the point (away from the edge).
    Eigen::Vector3d directionM = Eigen::Vector3d::UnitX();
};

/// The wave from `sourceM` diffracted over `path` to `pointM`: it travels on from where the path
/// leaves the box and has the free-field pressures at the distance L / D(theta), L the path
/// length and theta the angle the path turns in all, with D = (1 + cos theta) / 2, Kirchhoff's obliquity factor of Fresnel–Kirchhoff
/// diffraction (Born and Wolf, Principles of Optics, §8.3): no loss for a path that grazes the
/// edge, half the strength for one that turns a right angle. The stretch acts on distance,
/// so at long range (impulse ~ 1/R) the impulse scales by about D r / L.
DiffractedWave diffractedWave(const EdgePath& path, const Eigen::Vector3d& sourceM, const Eigen::Vector3d& pointM);

/// The diffracted wave's pulse at a face: the pressures, decays and shock speed of the free-field
/// pulse at the equivalent distance; arriving later than the direct wave by the extra path at
/// the direct wave's shock speed, and ending when the direct wave would (its negative phase
/// shortened by the delay), so that it is over when the direct wave's window has passed.
PointPulse diffractedPulse(const PointPulse& direct, const PointPulse& atEquivalentDistance, double extraPathM);

}  // namespace spall
