#include <spall/loads/Diffraction.h>

#include <algorithm>
#include <cmath>

namespace spall {

namespace {

/// The shortest path from a to b through a point of the segment from e0 to e1.
EdgePath pathOverSegment(const Eigen::Vector3d& e0, const Eigen::Vector3d& e1, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
    const Eigen::Vector3d along = e1 - e0;
    const double length = along.norm();
    const Eigen::Vector3d u = along / length;
    // Each end's position along the edge's line and its distance from the line; unfolded about
    // the line, the path is straight and crosses it where the distances divide it.
    const double sa = (a - e0).dot(u), sb = (b - e0).dot(u);
    const double da = (a - e0 - sa * u).norm(), db = (b - e0 - sb * u).norm();
    const double s = da + db > 0 ? sa + (sb - sa) * da / (da + db) : 0.5 * (sa + sb);
    EdgePath path;
    path.enterM = path.leaveM = e0 + std::clamp(s, 0.0, length) * u;
    path.lengthM = (a - path.enterM).norm() + (b - path.enterM).norm();
    return path;
}

}  // namespace

EdgePath shortestPathAround(const ObstacleBox& box, const Eigen::Vector3d& sourceM, const Eigen::Vector3d& pointM,
                            const StaticWorld& geometry, double groundToleranceM)
{
    const Eigen::Matrix3d rot = box.orientation.toRotationMatrix();
    const Eigen::Vector3d sight = pointM - sourceM;
    int across = 0;
    for (int axis = 1; axis < 3; ++axis)
        if (std::abs(rot.col(axis).dot(sight)) > std::abs(rot.col(across).dot(sight))) across = axis;
    const int u = (across + 1) % 3, v = (across + 2) % 3;
    const Eigen::Vector3d halfU = box.halfExtentM[u] * rot.col(u), halfV = box.halfExtentM[v] * rot.col(v);
    // Half the thickness, pointing from the source's side to the point's.
    const Eigen::Vector3d halfThickness = box.halfExtentM[across] * rot.col(across) * (rot.col(across).dot(sight) >= 0 ? 1.0 : -1.0);
    const Eigen::Vector3d corners[4] = {box.centreM - halfU - halfV, box.centreM + halfU - halfV, box.centreM + halfU + halfV,
                                        box.centreM - halfU + halfV};
    EdgePath best;
    best.lengthM = 1e300;
    const auto underground = [&](const Eigen::Vector3d& x) {
        return geometry.ground.enabled && x.dot(geometry.ground.normal) <= geometry.ground.offsetM + groundToleranceM;
    };
    for (int edge = 0; edge < 4; ++edge) {
        const Eigen::Vector3d &e0 = corners[edge], &e1 = corners[(edge + 1) % 4];
        if (underground(e0) && underground(e1)) continue;  // an edge along the ground: no way round there
        EdgePath path = pathOverSegment(e0, e1, sourceM, pointM);
        path.enterM -= halfThickness;
        path.leaveM += halfThickness;
        path.lengthM = (path.enterM - sourceM).norm() + 2.0 * halfThickness.norm() + (pointM - path.leaveM).norm();
        if (path.lengthM < best.lengthM) best = path;
    }
    if (best.lengthM == 1e300) best = {sight.norm(), sourceM, sourceM};  // every edge is underground: nothing to go round
    return best;
}

DiffractedWave diffractedWave(const EdgePath& path, const Eigen::Vector3d& sourceM, const Eigen::Vector3d& pointM)
{
    const Eigen::Vector3d in = path.enterM - sourceM, out = pointM - path.leaveM;
    DiffractedWave wave;
    const double inLength = in.norm(), outLength = out.norm();
    if (!(inLength > 0) || !(outLength > 0)) {
        // The point (or the source) is on the edge: the wave there is the direct one.
        wave.equivalentDistanceM = path.lengthM;
        wave.directionM = (pointM - sourceM).normalized();
        return wave;
    }
    const double cosTurn = std::clamp(in.dot(out) / (inLength * outLength), -1.0, 1.0);
    const double factor = std::max(0.5 * (1.0 + cosTurn), 1e-3);
    wave.equivalentDistanceM = path.lengthM / factor;
    wave.directionM = out / outLength;
    return wave;
}

PointPulse diffractedPulse(const PointPulse& direct, const PointPulse& atEquivalentDistance, double extraPathM)
{
    PointPulse pulse = atEquivalentDistance;
    const double delayS = std::max(0.0, extraPathM) / direct.shockSpeedMS;
    const double directEndS = direct.arrivalTimeS + direct.positiveDurationS + direct.negativeDurationS;
    pulse.arrivalTimeS = direct.arrivalTimeS + delayS;
    pulse.positiveDurationS = std::min(pulse.positiveDurationS, directEndS - pulse.arrivalTimeS);
    pulse.negativeDurationS = std::max(0.0, directEndS - pulse.arrivalTimeS - pulse.positiveDurationS);
    return pulse;
}

}  // namespace spall
