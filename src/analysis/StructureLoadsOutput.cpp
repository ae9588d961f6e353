// loads.h5, loads.vdb and loads_front.png (layout: docs/loads.md).
#include <spall/analysis/StructureLoads.h>

#include <spall/output/H5Out.h>
#include <spall/output/Png.h>
#include <spall/render/Render.h>
#include <spall/voxel/LinkBits.h>
#include <spall/voxel/VdbIo.h>

#include <algorithm>
#include <climits>
#include <cctype>
#include <cstdio>
#include <map>

namespace spall {

namespace {

template <typename Get>
std::vector<double> perFace(const ObjectLoads& object, Get get)
{
    std::vector<double> out;
    for (const FaceLoad& f : object.faces) {
        const auto v = get(f);
        if constexpr (std::is_same_v<decltype(v), const double>) out.push_back(v);
        else out.insert(out.end(), {v.x(), v.y(), v.z()});
    }
    return out;
}

void writeObject(H5Out& h5, const ObjectLoads& object, const std::string& group)
{
    h5.group(group.c_str());
    std::vector<int64_t> voxels, faces;
    for (const FaceLoad& f : object.faces) {
        voxels.insert(voxels.end(), {f.voxel.x(), f.voxel.y(), f.voxel.z()});
        faces.push_back(f.face);
    }
    const auto path = [&](const char* name) { return group + "/" + name; };
    h5.write(path("voxel_ijk").c_str(), voxels, 3);
    h5.write(path("face").c_str(), faces);
    h5.write(path("centre_m").c_str(), perFace(object, [](const FaceLoad& f) { return f.centreM; }), 3);
    h5.write(path("normal").c_str(), perFace(object, [](const FaceLoad& f) { return f.normal; }), 3);
    h5.write(path("peak_pressure_Pa").c_str(), perFace(object, [](const FaceLoad& f) { return f.peakPressurePa; }));
    h5.write(path("impulse_Pa_s").c_str(), perFace(object, [](const FaceLoad& f) { return f.impulsePaS; }));
    h5.write(path("negative_impulse_Pa_s").c_str(), perFace(object, [](const FaceLoad& f) { return f.negativeImpulsePaS; }));
    h5.write(path("arrival_time_s").c_str(), perFace(object, [](const FaceLoad& f) { return f.arrivalTimeS; }));
    const FrontFace& front = object.front;
    const char* g = group.c_str();
    h5.attribute(g, "voxel_size_m", object.voxelSizeM);
    h5.attribute(g, "net_impulse_x_N_s", object.netImpulseNS.x());
    h5.attribute(g, "net_impulse_y_N_s", object.netImpulseNS.y());
    h5.attribute(g, "net_impulse_z_N_s", object.netImpulseNS.z());
    h5.attribute(g, "front_face", int64_t(front.face));
    h5.attribute(g, "front_faces", int64_t(front.faces));
    h5.attribute(g, "front_mean_impulse_Pa_s", front.meanImpulsePaS);
    h5.attribute(g, "front_max_impulse_Pa_s", front.maxImpulsePaS);
    h5.attribute(g, "front_max_peak_pressure_Pa", front.maxPeakPressurePa);
    h5.attribute(g, "nearest_face", int64_t(front.nearest));
    h5.attribute(g, "nearest_charge", int64_t(front.charge));
    h5.attribute(g, "nearest_distance_m", front.distanceM);
    h5.attribute(g, "nearest_scaled_distance_m_kg13", front.scaledDistanceMKg13);
    h5.attribute(g, "nearest_cos_incidence", front.cosIncidence);
    h5.attribute(g, "reference_reflected_impulse_Pa_s", front.reflectedImpulsePaS);
    h5.attribute(g, "reference_reflected_pressure_Pa", front.reflectedPressurePa);
}

void writeH5(H5Out& h5, const StructureLoadsReport& report)
{
    h5.attribute("format_version", int64_t{1});
    h5.attribute("time_step_s", report.timeStepS);
    h5.attribute("end_time_s", report.endTimeS);
    h5.attribute("steps", report.steps);
    h5.group("/objects");
    for (const ObjectLoads& object : report.objects) writeObject(h5, object, "/objects/" + object.name);
}

/// Per object, its surface voxels holding the largest of their faces' values.
openvdb::GridPtrVec surfaceGrids(const StructureLoadsReport& report)
{
    openvdb::GridPtrVec grids;
    for (const ObjectLoads& object : report.objects) {
        const std::pair<const char*, double FaceLoad::*> fields[] = {{"impulse_Pa_s", &FaceLoad::impulsePaS},
                                                                     {"peak_pressure_Pa", &FaceLoad::peakPressurePa}};
        for (const auto& [name, field] : fields) {
            auto grid = openvdb::FloatGrid::create(0.0f);
            grid->setTransform(object.indexToWorld->copy());
            grid->setName(object.name + "." + name);
            auto acc = grid->getAccessor();
            for (const FaceLoad& f : object.faces) {
                const float value = float(f.*field);
                if (!acc.isValueOn(f.voxel) || value > acc.getValue(f.voxel)) acc.setValue(f.voxel, value);
            }
            grids.push_back(grid);
        }
    }
    return grids;
}

/// A blue–green–yellow ramp (viridis's ends and middle), 0 to 1.
Rgb ramp(double s)
{
    const Rgb stops[] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
    s = std::clamp(s, 0.0, 1.0) * 4;
    const int i = std::min(3, int(s));
    const double w = s - i;
    const auto mix = [&](uint8_t a, uint8_t b) { return uint8_t(std::lround(a + w * (b - a))); };
    return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g), mix(stops[i].b, stops[i + 1].b)};
}

std::string lower(std::string s)
{
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string number(const char* format, double value)
{
    char s[64];
    std::snprintf(s, sizeof s, format, value);
    return s;
}

/// The view of a front face from outside: right and up in world axes (up the object's axis
/// across the face nearer world z).
struct FaceView {
    Eigen::Vector3d right, up;
};

FaceView faceView(const ObjectLoads& object)
{
    const int axis = faceAxis(object.front.face);
    const Eigen::Vector3d normal = object.orientation * faceNormal(object.front.face);
    const Eigen::Vector3d a = object.orientation * Eigen::Vector3d::Unit((axis + 1) % 3);
    const Eigen::Vector3d b = object.orientation * Eigen::Vector3d::Unit((axis + 2) % 3);
    Eigen::Vector3d up = std::abs(a.z()) >= std::abs(b.z()) ? a : b;
    if (up.z() < 0 || (up.z() == 0 && up.y() < 0)) up = -up;
    return {(-normal).cross(up), up};
}

/// The front face as the charge sees it, a cell per voxel face coloured by impulse (the face
/// nearest the viewer where the surface steps), a colour bar, the point of the hand calculation
/// ringed and the charges as orange discs.
Image frontFacePicture(const ObjectLoads& object, const std::vector<Eigen::Vector3d>& chargesM)
{
    if (object.front.faces == 0) return Image(900, 600);
    const FaceView view = faceView(object);
    const Eigen::Vector3d normal = object.orientation * faceNormal(object.front.face);
    const double h = object.voxelSizeM;
    // Cells counted from the ringed face's, so rounding never meets a half.
    const FaceLoad& nearest = object.faces[object.front.nearest];
    const auto cellOf = [&](const Eigen::Vector3d& p) {
        return std::pair<long, long>{std::lround((p - nearest.centreM).dot(view.right) / h), std::lround((p - nearest.centreM).dot(view.up) / h)};
    };
    std::map<std::pair<long, long>, size_t> shown;  // cell -> face
    long u0 = LONG_MAX, u1 = LONG_MIN, v0 = LONG_MAX, v1 = LONG_MIN;
    for (size_t i = 0; i < object.faces.size(); ++i) {
        const FaceLoad& f = object.faces[i];
        if (f.face != object.front.face) continue;
        const std::pair<long, long> cell = cellOf(f.centreM);
        auto [at, isNew] = shown.emplace(cell, i);
        if (!isNew && f.centreM.dot(normal) > object.faces[at->second].centreM.dot(normal)) at->second = i;
        u0 = std::min(u0, cell.first), u1 = std::max(u1, cell.first), v0 = std::min(v0, cell.second), v1 = std::max(v1, cell.second);
    }
    const int width = 900, height = 600, left = 40, top = 60, plotW = 700, plotH = 460;
    Image img(width, height);
    const double maxImpulse = std::max(object.front.maxImpulsePaS, 1e-30);
    if (shown.empty()) return img;
    const int cell = std::max(1, std::min(plotW / int(u1 - u0 + 1), plotH / int(v1 - v0 + 1)));
    const int x0 = left + (plotW - cell * int(u1 - u0 + 1)) / 2, y0 = top + (plotH - cell * int(v1 - v0 + 1)) / 2;
    const auto px = [&](double u) { return x0 + (u - u0) * cell; };
    const auto py = [&](double v) { return y0 + (v1 - v) * cell; };
    for (const auto& [c, i] : shown)
        img.fillRect(int(px(c.first)), int(py(c.second)), int(px(c.first)) + cell, int(py(c.second)) + cell, ramp(object.faces[i].impulsePaS / maxImpulse));
    // The hand calculation's face (cell 0, 0), ringed in black.
    const int ring = cell / 2 + 3;
    const int cx = int(px(0)) + cell / 2, cy = int(py(0)) + cell / 2;
    img.line(cx - ring, cy - ring, cx + ring, cy - ring, {0, 0, 0}, 2);
    img.line(cx - ring, cy + ring, cx + ring, cy + ring, {0, 0, 0}, 2);
    img.line(cx - ring, cy - ring, cx - ring, cy + ring, {0, 0, 0}, 2);
    img.line(cx + ring, cy - ring, cx + ring, cy + ring, {0, 0, 0}, 2);
    for (const Eigen::Vector3d& c : chargesM) {
        const int x = int(px((c - nearest.centreM).dot(view.right) / h)) + cell / 2, y = int(py((c - nearest.centreM).dot(view.up) / h)) + cell / 2;
        if (x < left || x > left + plotW || y < top || y > top + plotH) continue;
        img.fillRect(x - 5, y - 5, x + 6, y + 6, kChargeColour);
    }
    // Colour bar, 0 at the bottom.
    const int barX = left + plotW + 30;
    for (int y = 0; y < plotH; ++y) img.fillRect(barX, top + y, barX + 24, top + y + 1, ramp(1.0 - double(y) / (plotH - 1)));
    const Rgb ink{60, 60, 60};
    img.text(barX + 30, top - 7, number("%.3g", maxImpulse), ink);
    img.text(barX + 30, top + plotH / 2 - 7, number("%.3g", maxImpulse / 2), ink);
    img.text(barX + 30, top + plotH - 7, "0", ink);
    img.text(barX - 10, top - 30, "pa s", ink);
    const char* names[] = {"-x", "+x", "-y", "+y", "-z", "+z"};
    img.text(10, 12, lower(object.name) + " front face (" + names[object.front.face] + "): blast impulse per area", ink);
    img.text(10, height - 50,
             "ringed: " + number("%.4g", nearest.impulsePaS) + " pa s, kingery-bulmash ir " + number("%.4g", object.front.reflectedImpulsePaS) +
                 " pa s at " + number("%.3g", object.front.distanceM) + " m",
             ink);
    img.text(10, height - 25, "peak " + number("%.4g", nearest.peakPressurePa) + " pa, pr " + number("%.4g", object.front.reflectedPressurePa) + " pa", ink);
    return img;
}

}  // namespace

void writeStructureLoads(const std::string& outDir, const StructureLoadsReport& report)
{
    writeH5FileAtomically(outDir + "/loads.h5", [&](H5Out& h5) { writeH5(h5, report); });
    writeGridsAtomically(outDir + "/loads.vdb", surfaceGrids(report));
    // The structure: the object whose front took the most impulse.
    const auto frontImpulse = [](const ObjectLoads& o) { return o.front.meanImpulsePaS * double(o.front.faces); };
    const auto structure = std::max_element(report.objects.begin(), report.objects.end(),
                                            [&](const ObjectLoads& a, const ObjectLoads& b) { return frontImpulse(a) < frontImpulse(b); });
    if (structure != report.objects.end()) writePng(outDir + "/loads_front.png", frontFacePicture(*structure, report.chargesM));
}

}  // namespace spall
