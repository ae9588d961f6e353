#include <spall/loads/BlastLoads.h>

#include <spall/core/Parallel.h>
#include <spall/loads/Exposure.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace spall {

namespace {

/// Faces per block of the parallel sums: blocks are summed in order, so results do not depend
/// on the thread count.
constexpr size_t kFaceBlock = 4096;

/// Runs perBlock(first, end) over fixed blocks of the body's faces, in parallel when there are several.
template <typename F>
void forEachFaceBlock(size_t faceCount, F&& perBlock)
{
    const size_t blocks = (faceCount + kFaceBlock - 1) / kFaceBlock;
    auto run = [&](size_t b) { perBlock(b, b * kFaceBlock, std::min(faceCount, (b + 1) * kFaceBlock)); };
    if (blocks == 1) {
        run(0);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t b = r.begin(); b != r.end(); ++b) run(b);
    });
}

}  // namespace

std::pair<double, double> distanceRangeM(const Body& body, const Eigen::Vector3d& pointM)
{
    const ObstacleBox bounds = worldBounds(body);
    double farthestM = 0.0;
    for (const Eigen::Vector3d& corner : cornersOf(bounds)) farthestM = std::max(farthestM, (corner - pointM).norm());
    return {std::max(0.0, -depthInsideM(bounds, pointM)), farthestM};
}

bool bodyInWindows(const Body& body, const BlastField& field, const std::vector<OpenWindow>& windows)
{
    for (const OpenWindow& w : windows) {
        const auto [nearestM, farthestM] = distanceRangeM(body, field.charges()[w.charge].positionM);
        if (farthestM >= w.minDistanceM && nearestM <= w.maxDistanceM) return true;
    }
    return false;
}

double Silhouette::clearingTimeS() const
{
    const double height = clearingHeightM();
    return spall::clearingTimeS(std::min(height, halfWidthM), std::max(height, halfWidthM), shockSpeedMS);
}

double Silhouette::rearRiseTimeS() const { return 4.0 * std::min(clearingHeightM(), halfWidthM) / shockSpeedMS; }

std::vector<const ObstacleBox*> heldBy(const std::vector<const Body*>& group, const std::vector<ObstacleBox>& obstacles)
{
    std::vector<const ObstacleBox*> holders;
    const auto anchored = [](const Body* body) { return body->anchored; };
    if (obstacles.empty() || std::none_of(group.begin(), group.end(), anchored)) return holders;
    std::vector<char> taken(obstacles.size(), 0);
    for (const Body* body : group) {
        if (!body->anchored) continue;
        const ObstacleBox bounds = worldBounds(*body);
        for (size_t i = 0; i < obstacles.size(); ++i)
            if (!taken[i] && boxesMeet(bounds, obstacles[i], 0.5 * body->voxelSizeM)) taken[i] = 1, holders.push_back(&obstacles[i]);
    }
    // Breadth first through obstacles that meet, within half the group's voxel.
    const double gapM = 0.5 * group.front()->voxelSizeM;
    for (size_t next = 0; next < holders.size(); ++next)
        for (size_t i = 0; i < obstacles.size(); ++i)
            if (!taken[i] && boxesMeet(*holders[next], obstacles[i], gapM)) taken[i] = 1, holders.push_back(&obstacles[i]);
    return holders;
}

Silhouette silhouetteOf(const std::vector<const Body*>& group, const std::vector<const ObstacleBox*>& holders, const Eigen::Vector3d& chargeM,
                        double shockSpeedMS, const GroundPlane& ground)
{
    // The corners of every member's oriented index box, and of the boxes that hold them, in the world.
    std::vector<Eigen::Vector3d> corners;
    for (const ObstacleBox* box : holders)
        for (const Eigen::Vector3d& corner : cornersOf(*box)) corners.push_back(corner);
    for (const Body* body : group) {
        const Eigen::Matrix3d rot = body->motion.orientation.toRotationMatrix();
        const openvdb::CoordBBox& box = body->indexBounds;
        for (int c = 0; c < 8; ++c) {
            const Eigen::Vector3d index((c & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5), (c & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5),
                                        (c & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5));
            corners.push_back(body->motion.positionM + rot * (index * body->voxelSizeM - body->mass.centreOfMassLocalM));
        }
    }
    Eigen::Vector3d lo = corners.front(), hi = corners.front();
    for (const Eigen::Vector3d& c : corners) lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
    Silhouette out;
    out.shockSpeedMS = shockSpeedMS;
    const Eigen::Vector3d sight = (0.5 * (lo + hi) - chargeM).normalized();
    const Eigen::Vector3d up = ground.enabled ? ground.normal : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d across = up - up.dot(sight) * sight;
    const Eigen::Vector3d vertical = across.norm() > 1e-6 ? Eigen::Vector3d(across.normalized()) : sight.unitOrthogonal();
    const Eigen::Vector3d horizontal = sight.cross(vertical);
    double uLo = 1e300, uHi = -1e300, vLo = 1e300, vHi = -1e300, lowestM = 1e300;
    for (const Eigen::Vector3d& c : corners) {
        uLo = std::min(uLo, c.dot(horizontal)), uHi = std::max(uHi, c.dot(horizontal));
        vLo = std::min(vLo, c.dot(vertical)), vHi = std::max(vHi, c.dot(vertical));
        lowestM = std::min(lowestM, c.dot(up));
    }
    out.halfWidthM = 0.5 * (uHi - uLo);
    out.halfHeightM = 0.5 * (vHi - vLo);
    out.onGround = ground.enabled && lowestM <= ground.offsetM + 0.5 * group.front()->voxelSizeM;
    return out;
}

BlastLoads::BlastLoads(const BlastField& field, const std::vector<OpenWindow>& windows, const LoadSettings& settings,
                       const StaticWorld& geometry)
    : mField(field), mWindows(windows), mSettings(settings), mGeometry(geometry), mFromGround(windows.size(), 0)
{
    const GroundPlane& ground = mGeometry.ground;
    for (size_t w = 0; w < windows.size(); ++w)
        mFromGround[w] = ground.enabled && field.charges()[windows[w].charge].positionM.dot(ground.normal) < ground.offsetM;
}

bool BlastLoads::onGround(const Eigen::Vector3d& faceCentreM, const Eigen::Vector3d& normal, double voxelSizeM) const
{
    const GroundPlane& ground = mGeometry.ground;
    return ground.enabled && normal.dot(ground.normal) < -0.5 && faceCentreM.dot(ground.normal) - ground.offsetM <= 0.5 * voxelSizeM;
}

const ObstacleBox* BlastLoads::shadowCaster(const Eigen::Vector3d& xM, const Eigen::Vector3d& chargeM, const Exposure* exposure,
                                             size_t excludeGroup) const
{
    for (const ObstacleBox& box : mGeometry.boxes)
        if (segmentMeetsBox(xM, chargeM, box)) return &box;
    if (!exposure) return nullptr;
    const int64_t body = exposure->firstBlocker(xM, chargeM, excludeGroup);
    return body >= 0 ? &exposure->groupBoundsOf(size_t(body)) : nullptr;
}

FaceWave BlastLoads::waveOnFace(const OpenWindow& window, const PointPulse& direct, const Eigen::Vector3d& probeM,
                                const Eigen::Vector3d& directTravel, const Exposure* exposure, size_t excludeGroup, double groundToleranceM) const
{
    const Eigen::Vector3d& charge = mField.charges()[window.charge].positionM;
    const ObstacleBox* caster = shadowCaster(probeM, charge, exposure, excludeGroup);
    if (!caster) return {direct, directTravel, false};
    const EdgePath path = shortestPathAround(*caster, charge, probeM, mGeometry, groundToleranceM);
    const DiffractedWave wave = diffractedWave(path, charge, probeM);
    const double equivalent = wave.equivalentDistanceM;
    return {diffractedPulse(direct, mField.pulseAt(window.charge, equivalent * equivalent), path.lengthM - (probeM - charge).norm()),
            wave.directionM, true};
}

std::vector<char> BlastLoads::loadedBodies(const std::vector<Body>& bodies) const
{
    std::vector<char> loaded(bodies.size(), 0);
    forEachIndex(bodies.size(), [&](size_t i) { loaded[i] = !bodies[i].anchored && bodyInWindows(bodies[i], mField, mWindows); },
                 kCheapGrain);
    return loaded;
}

std::vector<Silhouette> BlastLoads::silhouettes(const std::vector<const Body*>& group) const
{
    std::vector<Silhouette> outlines(mWindows.size());
    if (mSettings.model != LoadModel::BlastEngineering) return outlines;
    const std::vector<const ObstacleBox*> holders = heldBy(group, mGeometry.boxes);
    for (size_t w = 0; w < mWindows.size(); ++w) {
        const Eigen::Vector3d& charge = mField.charges()[mWindows[w].charge].positionM;
        const double speed = mField.pulseAt(mWindows[w].charge, (group.front()->motion.positionM - charge).squaredNorm()).shockSpeedMS;
        outlines[w] = silhouetteOf(group, holders, charge, speed, mGeometry.ground);
    }
    return outlines;
}

namespace {

/// Whether an exposed face lies on the side of its body's index bounds it faces.
bool onIndexBounds(const Body& body, const ExposedFace& face)
{
    const int axis = faceAxis(face.face);
    return face.voxel[axis] == (faceSign(face.face) > 0 ? body.indexBounds.max()[axis] : body.indexBounds.min()[axis]);
}

}  // namespace

template <typename F>
void BlastLoads::forEachFaceImpulse(const Body& body, const std::vector<Silhouette>& outlines, const Exposure* exposure, size_t bodyIndex,
                                    double timeS, double dtS, size_t firstFace, size_t endFace, F&& f) const
{
    const double h = body.voxelSizeM, area = h * h;
    const Eigen::Matrix3d rot = body.motion.orientation.toRotationMatrix();
    const double p0 = mField.settings().atmosphere.pressurePa;
    for (size_t i = firstFace; i < endFace; ++i) {
        if (exposure && exposure->covered(bodyIndex, i)) continue;  // pressed against another body: no air there
        const ExposedFace& face = body.exposedFaces[i];
        const Eigen::Vector3d normal = rot.col(faceAxis(face.face)) * faceSign(face.face);
        const Eigen::Vector3d arm = rot * body.voxelOffsetM(face.voxel) + 0.5 * h * normal;
        const Eigen::Vector3d x = body.motion.positionM + arm;
        if (onGround(x, normal, h)) continue;  // resting on the ground: no air there
        for (size_t w = 0; w < mWindows.size(); ++w) {
            const OpenWindow& window = mWindows[w];
            const Eigen::Vector3d r = x - mField.charges()[window.charge].positionM;
            const double r2 = r.squaredNorm();
            if (r2 < window.minDistanceM * window.minDistanceM || r2 > window.maxDistanceM * window.maxDistanceM || r2 <= 0) continue;
            const Eigen::Vector3d rHat = r / std::sqrt(r2);
            const double cosine = -normal.dot(rHat);
            // The ground's reflection (an image charge) loads only faces that look toward the
            // ground it comes from: it does not wrap round bodies standing on that ground.
            if (cosine <= 0.0 && mFromGround[w]) continue;
            if (mSettings.model == LoadModel::BlastEngineering) {
                const PointPulse direct = mField.pulseAt(window.charge, r2);
                if (timeS + dtS <= direct.arrivalTimeS || timeS >= direct.arrivalTimeS + direct.positiveDurationS + direct.negativeDurationS)
                    continue;
                // A face that looks at the charge is shadowed by anything, its own body too (a
                // concave pocket) unless the face lies on its body's bounds, which the ray leaves
                // at once and cannot meet again (a box is convex); one that looks away only by
                // something outside the group of bodies pressed together that is loaded as one
                // object with it.
                const bool ownBodyCannotShadow = exposure && exposure->alone(bodyIndex) && onIndexBounds(body, face);
                const size_t excludeGroup =
                    (cosine > 0.0 && !ownBodyCannotShadow) || !exposure ? Exposure::kNoBody : exposure->groupOf()[bodyIndex];
                const FaceWave wave = waveOnFace(window, direct, x + 0.5 * h * normal, rHat, exposure, excludeGroup, 0.5 * h);
                const double from = timeS - wave.pulse.arrivalTimeS;
                FaceExposure face =
                    faceExposure(wave.pulse, -normal.dot(wave.travel), outlines[w].clearingTimeS(), outlines[w].rearRiseTimeS(), p0);
                // UFC 3-340-02 §2-15.3: the wave that spills round an edge loads the roof, side
                // and rear walls with its side-on pressure and drag; none of them reflects it.
                if (wave.diffracted) face.reflectedFraction = 0.0;
                const double impulse = faceImpulsePaS(wave.pulse, face, from, from + dtS, p0);
                if (impulse != 0.0) f(i, Eigen::Vector3d(-impulse * area * normal), arm, normal);
                continue;
            }
            // The paper's rule, sampled at the step's start, on faces that look at the charge.
            const double p = mField.chargeOverpressurePa(window.charge, std::sqrt(r2), timeS);
            if (cosine <= 0.0 || p == 0.0) continue;
            const double pressure = mSettings.model == LoadModel::PaperReflected && p > 0
                                        ? p + (rankineHugoniotReflected(p, p0) - p) * cosine * cosine
                                        : p;
            f(i, Eigen::Vector3d(pressure * area * cosine * dtS * rHat), arm, normal);
        }
    }
}

Wrench BlastLoads::wrenchOf(const Body& body, const std::vector<Silhouette>& outlines, const Exposure* exposure, size_t bodyIndex,
                            double timeS, double dtS, std::vector<Eigen::Vector3d>* faceForcesN) const
{
    Wrench total;
    if (faceForcesN) faceForcesN->assign(body.exposedFaces.size(), Eigen::Vector3d::Zero());
    if (mWindows.empty() || body.exposedFaces.empty() || !(dtS > 0)) return total;
    std::vector<Wrench> partial((body.exposedFaces.size() + kFaceBlock - 1) / kFaceBlock);
    forEachFaceBlock(body.exposedFaces.size(), [&](size_t block, size_t first, size_t end) {
        Wrench w;
        forEachFaceImpulse(body, outlines, exposure, bodyIndex, timeS, dtS, first, end,
                           [&](size_t face, const Eigen::Vector3d& impulse, const Eigen::Vector3d& arm, const Eigen::Vector3d&) {
                               w.forceN += impulse;
                               w.torqueNm += arm.cross(impulse);
                               if (faceForcesN) (*faceForcesN)[face] += impulse / dtS;
                           });
        partial[block] = w;
    });
    for (const Wrench& w : partial) {
        total.forceN += w.forceN / dtS;
        total.torqueNm += w.torqueNm / dtS;
    }
    return total;
}

Wrench BlastLoads::stepWrench(const Body& body, double timeS, double dtS) const
{
    return wrenchOf(body, silhouettes({&body}), nullptr, 0, timeS, dtS);
}

std::vector<Wrench> BlastLoads::stepWrenches(const std::vector<Body>& bodies, const std::vector<char>& loaded, double timeS,
                                             double dtS, FaceForces* faces) const
{
    std::vector<Wrench> wrenches(bodies.size());
    std::vector<char> wanted = loaded;
    if (faces) {
        // Each body's faces emptied, their storage kept for the next step's.
        faces->forceN.resize(bodies.size());
        for (std::vector<Eigen::Vector3d>& forces : faces->forceN) forces.clear();
        // A body the wave is not crossing takes no force on any face: its zeros need no exposure.
        for (size_t i = 0; i < bodies.size(); ++i) {
            if (!faces->wanted[i]) continue;
            if (wanted[i] || bodyInWindows(bodies[i], mField, mWindows))
                wanted[i] = 1;
            else
                faces->forceN[i].assign(bodies[i].exposedFaces.size(), Eigen::Vector3d::Zero());
        }
    }
    auto faceForcesOf = [&](size_t i) { return faces && faces->wanted[i] ? &faces->forceN[i] : nullptr; };
    if (std::find(wanted.begin(), wanted.end(), 1) == wanted.end()) return wrenches;  // the wave is past every body
    if (mSettings.model != LoadModel::BlastEngineering) {
        forEachIndex(bodies.size(), [&](size_t i) {
            if (wanted[i]) wrenches[i] = wrenchOf(bodies[i], silhouettes({&bodies[i]}), nullptr, 0, timeS, dtS, faceForcesOf(i));
        });
        return wrenches;
    }
    // Every body the wave has reached covers faces and casts shadows, anchored and resting ones too.
    std::vector<char> reached(bodies.size());
    forEachIndex(bodies.size(), [&](size_t i) {
        for (const OpenWindow& w : mWindows)
            if ((bodies[i].motion.positionM - mField.charges()[w.charge].positionM).norm() - bodies[i].boundingRadiusM <= w.maxDistanceM)
                reached[i] = 1;
    }, kCheapGrain);
    const Exposure exposure(bodies, reached);
    std::vector<std::vector<const Body*>> members(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i)
        if (reached[i]) members[exposure.groupOf()[i]].push_back(&bodies[i]);
    std::vector<std::vector<Silhouette>> outlines(bodies.size());
    forEachIndex(bodies.size(), [&](size_t g) {
        if (!members[g].empty()) outlines[g] = silhouettes(members[g]);
    });
    forEachIndex(bodies.size(), [&](size_t i) {
        if (wanted[i]) wrenches[i] = wrenchOf(bodies[i], outlines[exposure.groupOf()[i]], &exposure, i, timeS, dtS, faceForcesOf(i));
    });
    return wrenches;
}

std::vector<double> BlastLoads::faceImpulsesPaS(const Body& body, double timeS, double dtS) const
{
    std::vector<double> perFace(body.exposedFaces.size(), 0.0);
    if (mWindows.empty() || body.exposedFaces.empty()) return perFace;
    const std::vector<Silhouette> outlines = silhouettes({&body});
    const double area = body.voxelSizeM * body.voxelSizeM;
    forEachFaceBlock(body.exposedFaces.size(), [&](size_t, size_t first, size_t end) {
        forEachFaceImpulse(body, outlines, nullptr, 0, timeS, dtS, first, end,
                           [&](size_t i, const Eigen::Vector3d& impulse, const Eigen::Vector3d&, const Eigen::Vector3d& normal) {
                               perFace[i] -= impulse.dot(normal) / area;
                           });
    });
    return perFace;
}

}  // namespace spall
