// The blast over a scene's objects held still, face by face (analysis/StructureLoads.h).
#include <spall/analysis/StructureLoads.h>

#include <spall/core/Error.h>
#include <spall/core/Parallel.h>
#include <spall/voxel/LinkBits.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spall {

namespace {

constexpr int kPeakSubsteps = 25;

/// The span of time in which some charge's wave is at some exposed face, and the shortest
/// positive phase any face meets.
struct LoadingSpan {
    double startS = std::numeric_limits<double>::infinity(), endS = -std::numeric_limits<double>::infinity();
    double shortestPositiveS = std::numeric_limits<double>::infinity();
};

LoadingSpan loadingSpan(const std::vector<ObjectLoads>& objects, const BlastField& field)
{
    LoadingSpan span;
    const std::vector<Charge>& charges = field.charges();
    for (const ObjectLoads& object : objects)
        for (size_t c = 0; c < charges.size(); ++c) {
            double nearestM = std::numeric_limits<double>::infinity(), farthestM = 0;
            for (const FaceLoad& f : object.faces) {
                const double d = (f.centreM - charges[c].positionM).norm();
                nearestM = std::min(nearestM, d), farthestM = std::max(farthestM, d);
            }
            if (object.faces.empty()) continue;
            nearestM = std::max(0.5 * object.voxelSizeM, nearestM - object.voxelSizeM);
            span.startS = std::min(span.startS, field.window(int(c), nearestM).first);
            span.endS = std::max(span.endS, field.window(int(c), farthestM + object.voxelSizeM).second);
            const BlastParameters p = blastParameters(field.settings().dataset, charges[c].burst, charges[c].tntKg, nearestM, field.settings().atmosphere);
            span.shortestPositiveS = std::min(span.shortestPositiveS, p.positiveDurationS);
        }
    return span;
}

/// An object's name as a key of loads.h5 and loads.vdb: '/' (an HDF5 path separator) made '_', and
/// `_<index>` appended when an earlier object has it.
std::string uniqueName(std::string name, size_t index, const std::vector<ObjectLoads>& earlier)
{
    std::replace(name.begin(), name.end(), '/', '_');
    const auto taken = [&](const std::string& n) { return std::any_of(earlier.begin(), earlier.end(), [&](const ObjectLoads& o) { return o.name == n; }); };
    return taken(name) ? name + "_" + std::to_string(index) : name;
}

std::vector<ObjectLoads> emptyLoads(const Simulation& simulation)
{
    std::vector<ObjectLoads> objects;
    for (size_t i = 0; i < simulation.bodies().size(); ++i) {
        const Body& body = simulation.bodies()[i];
        ObjectLoads object;
        object.name = uniqueName(simulation.scene().objects.at(i).name, i, objects);
        object.voxelSizeM = body.voxelSizeM;
        object.indexToWorld = body.indexToWorld();
        object.orientation = body.motion.orientation;
        for (const ExposedFace& f : body.exposedFaces) {
            FaceLoad load;
            load.voxel = f.voxel;
            load.face = f.face;
            load.normal = body.motion.orientation * faceNormal(f.face);
            load.centreM = body.voxelWorldM(f.voxel) + 0.5 * body.voxelSizeM * load.normal;
            object.faces.push_back(load);
        }
        objects.push_back(std::move(object));
    }
    return objects;
}

/// The distances each charge's wave loads at some time in [t, t + dt]: the window at t widened to
/// the front at t + dt, so no face the wave reaches within the step is skipped (the run's steps
/// are short enough that it does not matter there; these are not).
std::vector<OpenWindow> windowsOver(const BlastField& field, double timeS, double dtS)
{
    std::vector<OpenWindow> windows = field.openWindows(timeS);
    for (const OpenWindow& later : field.openWindows(timeS + dtS)) {
        const auto same = std::find_if(windows.begin(), windows.end(), [&](const OpenWindow& w) { return w.charge == later.charge; });
        if (same == windows.end()) windows.push_back(later);
        else same->maxDistanceM = std::max(same->maxDistanceM, later.maxDistanceM);
    }
    return windows;
}

/// The mean overpressure pushing into each face over a step, per body (empty for bodies no
/// window reaches).
std::vector<std::vector<double>> facePressuresPa(const Simulation& simulation, const std::vector<ObjectLoads>& objects, double timeS, double dtS)
{
    const BlastField& field = simulation.field();
    const std::vector<Body>& bodies = simulation.bodies();
    std::vector<std::vector<double>> pressures(bodies.size());
    const std::vector<OpenWindow> windows = windowsOver(field, timeS, dtS);
    if (windows.empty()) return pressures;
    FaceForces faces;
    faces.wanted.assign(bodies.size(), 1);
    const BlastLoads loads(field, windows, simulation.scene().loads, simulation.staticWorld());
    loads.stepWrenches(bodies, std::vector<char>(bodies.size(), 0), timeS, dtS, &faces);
    for (size_t b = 0; b < bodies.size(); ++b) {
        const double area = objects[b].voxelSizeM * objects[b].voxelSizeM;
        for (size_t i = 0; i < faces.forceN[b].size(); ++i) pressures[b].push_back(-faces.forceN[b][i].dot(objects[b].faces[i].normal) / area);
    }
    return pressures;
}

/// Adds one step's impulses to the faces' records.
void addImpulses(ObjectLoads& object, const std::vector<double>& pressuresPa, double dtS)
{
    const double area = object.voxelSizeM * object.voxelSizeM;
    for (size_t i = 0; i < pressuresPa.size(); ++i) {
        (pressuresPa[i] > 0 ? object.faces[i].impulsePaS : object.faces[i].negativeImpulsePaS) += pressuresPa[i] * dtS;
        object.netImpulseNS -= object.faces[i].normal * (pressuresPa[i] * area * dtS);
    }
}

/// Raises the faces' peaks and marks their arrival from one (sub)step's mean pressures.
void notePeaks(ObjectLoads& object, const std::vector<double>& pressuresPa, double timeS)
{
    for (size_t i = 0; i < pressuresPa.size(); ++i) {
        FaceLoad& face = object.faces[i];
        if (pressuresPa[i] == 0.0) continue;
        face.peakPressurePa = std::max(face.peakPressurePa, pressuresPa[i]);
        if (face.arrivalTimeS < 0) face.arrivalTimeS = timeS;
    }
}

/// True when a wave arrives at some face within the step: its mean overpressure turns positive,
/// or jumps by half (a second charge's wave), so the step's mean may hide its peak. (A rear
/// face's load that builds up over its rise time peaks at the end of the rise, where a step's
/// mean misses it by half a step's rise at most.)
bool waveArrives(const std::vector<std::vector<double>>& now, const std::vector<std::vector<double>>& before)
{
    for (size_t b = 0; b < now.size(); ++b)
        for (size_t i = 0; i < now[b].size(); ++i) {
            const double previous = i < before[b].size() ? before[b][i] : 0.0;
            if (now[b][i] > 0.0 && (previous <= 0.0 || now[b][i] > 1.5 * previous)) return true;
        }
    return false;
}

/// The axis direction whose faces took the most impulse, and the hand calculation at its face
/// nearest a charge in scaled distance.
FrontFace frontFaceOf(const ObjectLoads& object, const BlastField& field, size_t sceneCharges)
{
    FrontFace front;
    double byDirection[6] = {};
    for (const FaceLoad& f : object.faces) byDirection[f.face] += f.impulsePaS;
    front.face = int(std::max_element(std::begin(byDirection), std::end(byDirection)) - std::begin(byDirection));
    double nearestZ = std::numeric_limits<double>::infinity(), sum = 0;
    const std::vector<Charge>& charges = field.charges();
    for (size_t i = 0; i < object.faces.size(); ++i) {
        const FaceLoad& f = object.faces[i];
        if (f.face != front.face) continue;
        ++front.faces;
        sum += f.impulsePaS;
        front.maxImpulsePaS = std::max(front.maxImpulsePaS, f.impulsePaS);
        front.maxPeakPressurePa = std::max(front.maxPeakPressurePa, f.peakPressurePa);
        for (size_t c = 0; c < sceneCharges; ++c) {  // the field's ground images follow them
            const double distanceM = (f.centreM - charges[c].positionM).norm();
            const double z = distanceM / std::cbrt(charges[c].tntKg * (charges[c].burst == BurstType::Surface ? 2.0 : 1.0));
            if (z >= nearestZ) continue;
            nearestZ = z;
            front.nearest = i, front.charge = int(c), front.distanceM = distanceM, front.scaledDistanceMKg13 = z;
            front.cosIncidence = -f.normal.dot((f.centreM - charges[c].positionM) / distanceM);
        }
    }
    if (front.faces == 0) return front;
    front.meanImpulsePaS = sum / double(front.faces);
    const Charge& charge = charges[front.charge];
    const BlastParameters p = blastParameters(field.settings().dataset, charge.burst, charge.tntKg, front.distanceM, field.settings().atmosphere);
    front.reflectedImpulsePaS = p.reflectedImpulsePaS;
    front.reflectedPressurePa = p.reflectedPressurePa;
    return front;
}

}  // namespace

StructureLoadsReport structureLoads(const Simulation& simulation, const std::function<void(int64_t, int64_t)>& onStep)
{
    const BlastField& field = simulation.field();
    if (field.charges().empty()) throw InputError(simulation.scene().sourceName + ": charges: none, so no blast loads anything");
    const std::vector<Body>& bodies = simulation.bodies();
    StructureLoadsReport report;
    report.objects = emptyLoads(simulation);
    for (const Charge& charge : simulation.scene().charges) report.chargesM.push_back(charge.positionM);
    const LoadingSpan span = loadingSpan(report.objects, field);
    if (!(span.endS > span.startS)) throw InputError(simulation.scene().sourceName + ": objects: none has a face the blast can load");
    // Impulses are exact over any step (loads/FacePulse.h); steps of 1/20 of the shortest
    // positive phase keep the split into positive and negative impulse sharp. Peaks are the
    // largest mean over a substep of 1/500 of it, taken where a wave arrives: the mean over the
    // first substep of a Friedlander pulse of decay b is within b/1000 of its peak.
    report.timeStepS = span.shortestPositiveS / 20;
    report.endTimeS = span.endS;
    const int64_t steps = int64_t(std::ceil((span.endS - span.startS) / report.timeStepS));
    std::vector<std::vector<double>> before(bodies.size());
    for (int64_t k = 0; k < steps; ++k) {
        const double t = span.startS + double(k) * report.timeStepS;
        const std::vector<std::vector<double>> now = facePressuresPa(simulation, report.objects, t, report.timeStepS);
        for (size_t b = 0; b < bodies.size(); ++b) addImpulses(report.objects[b], now[b], report.timeStepS);
        if (waveArrives(now, before)) {
            const double dt = report.timeStepS / kPeakSubsteps;
            std::vector<std::vector<std::vector<double>>> sub(kPeakSubsteps);
            forEachIndex(sub.size(), [&](size_t j) { sub[j] = facePressuresPa(simulation, report.objects, t + double(j) * dt, dt); });
            for (size_t j = 0; j < sub.size(); ++j)
                for (size_t b = 0; b < bodies.size(); ++b) notePeaks(report.objects[b], sub[j][b], t + double(j) * dt);
        } else {
            for (size_t b = 0; b < bodies.size(); ++b) notePeaks(report.objects[b], now[b], t);
        }
        before = now;
        if (onStep) onStep(k + 1, steps);
    }
    report.steps = steps;
    for (ObjectLoads& object : report.objects) object.front = frontFaceOf(object, field, simulation.scene().charges.size());
    return report;
}

}  // namespace spall
