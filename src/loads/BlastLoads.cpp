#include <spall/loads/BlastLoads.h>

#include <spall/core/Parallel.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace spall {

bool bodyInWindows(const Body& body, const BlastField& field, const std::vector<OpenWindow>& windows)
{
    for (const OpenWindow& w : windows) {
        const double d = (body.motion.positionM - field.charges()[w.charge].positionM).norm();
        if (d + body.boundingRadiusM >= w.minDistanceM && d - body.boundingRadiusM <= w.maxDistanceM) return true;
    }
    return false;
}

std::vector<char> BlastLoads::loadedBodies(const std::vector<Body>& bodies) const
{
    std::vector<char> loaded(bodies.size(), 0);
    forEachIndex(bodies.size(), [&](size_t i) { loaded[i] = !bodies[i].anchored && bodyInWindows(bodies[i], mField, mWindows); },
                 kCheapGrain);
    return loaded;
}

Wrench BlastLoads::wrench(const Body& body, double timeS, const Eigen::Vector3d& positionM, const Eigen::Quaterniond& orientation) const
{
    const BlastField& field = mField;
    const std::vector<OpenWindow>& windows = mWindows;
    Wrench total;
    if (windows.empty() || body.exposedFaces.empty()) return total;
    const double h = body.voxelSizeM;
    const double faceArea = h * h;
    const Eigen::Matrix3d rot = orientation.toRotationMatrix();
    const double p0 = field.settings().atmosphere.pressurePa;
    constexpr size_t kBlock = 4096;
    const size_t blocks = (body.exposedFaces.size() + kBlock - 1) / kBlock;
    std::vector<Wrench> partial(blocks);
    auto sumBlock = [&](size_t b) {
        Wrench w;
        const size_t end = std::min(body.exposedFaces.size(), (b + 1) * kBlock);
        for (size_t i = b * kBlock; i < end; ++i) {
            const ExposedFace& f = body.exposedFaces[i];
            const Eigen::Vector3d normal = rot.col(faceAxis(f.face)) * faceSign(f.face);
            const Eigen::Vector3d arm = rot * body.voxelOffsetM(f.voxel) + 0.5 * h * normal;
            const Eigen::Vector3d x = positionM + arm;
            field.forEachCharge(x, timeS, windows, [&](int, double p, const Eigen::Vector3d& charge) {
                const Eigen::Vector3d r = x - charge;
                const double distance = r.norm();
                if (distance <= 0) return;
                const Eigen::Vector3d rHat = r / distance;
                const double cosine = -normal.dot(rHat);
                if (cosine <= 0.0) return;  // the face looks away from this charge
                double pressure = p;
                if (mSettings.reflectedPressure && p > 0) {
                    const double reflected = rankineHugoniotReflected(p, p0);
                    pressure = p + (reflected - p) * cosine * cosine;
                }
                const Eigen::Vector3d force = pressure * faceArea * cosine * rHat;
                w.forceN += force;
                w.torqueNm += arm.cross(force);
            });
        }
        partial[b] = w;
    };
    if (blocks == 1) {
        sumBlock(0);
    } else {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t b = r.begin(); b != r.end(); ++b) sumBlock(b);
        });
    }
    for (const Wrench& w : partial) {
        total.forceN += w.forceN;
        total.torqueNm += w.torqueNm;
    }
    return total;
}

}  // namespace spall
