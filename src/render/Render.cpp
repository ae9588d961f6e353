#include <spall/render/Render.h>

#include <spall/core/Error.h>
#include <spall/output/FragmentSurface.h>
#include <spall/voxel/VdbIo.h>

#include <openvdb/io/File.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <filesystem>

namespace spall {

namespace {

Eigen::Vector3d toEigen(const openvdb::Vec3d& v) { return {v.x(), v.y(), v.z()}; }

/// A fragment colour from its id: evenly spread hues, fixed saturation and value.
Rgb fragmentColour(int64_t id)
{
    const double hue = std::fmod(double(uint64_t(id) * 0x9E3779B97F4A7C15ull >> 11) * (1.0 / 9007199254740992.0), 1.0) * 6.0;
    const double s = 0.55, v = 0.9;
    const int i = static_cast<int>(hue);
    const double f = hue - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    double r, g, b;
    switch (i % 6) {
    case 0: r = v, g = t, b = p; break;
    case 1: r = q, g = v, b = p; break;
    case 2: r = p, g = v, b = t; break;
    case 3: r = p, g = q, b = v; break;
    case 4: r = t, g = p, b = v; break;
    default: r = v, g = p, b = q; break;
    }
    return {uint8_t(r * 255), uint8_t(g * 255), uint8_t(b * 255)};
}

struct View {
    Eigen::Matrix3d toCamera;  ///< rows: right, up, -forward
    Eigen::Vector3d eye;
    double focal;              ///< pixels
    double cx, cy;
    /// Pixel coordinates and depth (> 0 in front of the camera).
    Eigen::Vector3d project(const Eigen::Vector3d& world) const
    {
        const Eigen::Vector3d c = toCamera * (world - eye);
        const double depth = -c.z();
        return {cx + focal * c.x() / depth, cy - focal * c.y() / depth, depth};
    }
};

View makeView(const Camera& camera, const RenderSettings& s)
{
    const Eigen::Vector3d forward = (camera.targetM - camera.eyeM).normalized();
    Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
    if (right.norm() < 1e-9) right = Eigen::Vector3d::UnitX();
    right.normalize();
    const Eigen::Vector3d up = right.cross(forward);
    View v;
    v.toCamera.row(0) = right;
    v.toCamera.row(1) = up;
    v.toCamera.row(2) = -forward;
    v.eye = camera.eyeM;
    v.focal = 0.5 * s.height / std::tan(0.5 * camera.verticalFovDeg * M_PI / 180.0);
    v.cx = 0.5 * s.width;
    v.cy = 0.5 * s.height;
    return v;
}

void rasteriseTriangle(Image& img, std::vector<float>& depth, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                       const Eigen::Vector3d& c, Rgb colour)
{
    if (a.z() <= 1e-3 || b.z() <= 1e-3 || c.z() <= 1e-3) return;  // behind the camera: skip
    const int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(img.width() - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(img.height() - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) return;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const double px = x + 0.5, py = y + 0.5;
            const double w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
            const double w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
            const double w2 = 1.0 - w0 - w1;
            if (w0 < 0 || w1 < 0 || w2 < 0) continue;
            const float z = float(w0 * a.z() + w1 * b.z() + w2 * c.z());
            float& d = depth[size_t(y) * img.width() + x];
            if (z < d) {
                d = z;
                img.set(x, y, colour);
            }
        }
}

}  // namespace

FrameGrids readFrame(const std::string& path)
{
    initialiseOpenVdb();
    FrameGrids out;
    try {
        openvdb::io::File file(path);
        file.open();
        auto meta = file.getMetadata();
        if (auto f = meta->getMetadata<openvdb::Int32Metadata>("frame")) out.frame = f->value();
        if (auto t = meta->getMetadata<openvdb::DoubleMetadata>("time_s")) out.timeS = t->value();
        std::unordered_map<int64_t, openvdb::FloatTree::Ptr> voxelsByMeshKey;
        for (auto it = file.beginName(); it != file.endName(); ++it) {
            const std::string name = it.gridName();
            if (name.rfind("fragment_", 0) != 0) continue;
            openvdb::FloatGrid::ConstPtr grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(file.readGrid(name));
            if (!grid) continue;
            if (grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
                const auto k = grid->getMetadata<openvdb::Int32Metadata>("level_set_subdivisions");
                if (!k) throw IoError(path + ": " + name + ": a level set without level_set_subdivisions metadata");
                // Fragments of one shape (one mesh_key) convert to the same voxels: convert once.
                auto& voxels = voxelsByMeshKey[grid->metaValue<int64_t>("mesh_key")];
                if (!voxels) voxels = voxelsOfLevelSet(*grid, k->value())->treePtr();
                auto placed = openvdb::FloatGrid::create(voxels);
                placed->setTransform(voxelTransformOf(grid->transform(), k->value()));
                grid = placed;
            }
            out.fragments.push_back(grid);
            out.ids.push_back(std::stoll(name.substr(9)));
        }
        file.close();
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read as a spall frame: " + e.what());
    }
    return out;
}

std::vector<FragmentRef> fragmentsOf(const FrameGrids& frame)
{
    std::vector<FragmentRef> out;
    for (size_t i = 0; i < frame.fragments.size(); ++i)
        out.push_back({frame.fragments[i].get(), frame.fragments[i]->transform().copy(), frame.ids[i]});
    return out;
}

std::vector<FragmentRef> fragmentsOf(const std::vector<Body>& bodies)
{
    std::vector<FragmentRef> out;
    for (const Body& b : bodies) out.push_back({b.grid.get(), b.indexToWorld(), b.id});
    return out;
}

namespace {

/// Calls f(grid) with the grid's concrete type.
template <typename F>
void withGrid(const openvdb::GridBase* grid, F&& f)
{
    if (auto g = dynamic_cast<const openvdb::FloatGrid*>(grid))
        f(*g);
    else if (auto l = dynamic_cast<const LinkGrid*>(grid))
        f(*l);
}

/// The value below which a fraction q of the total weight lies.
double weightedQuantile(std::vector<std::pair<double, double>> valueAndWeight, double q)
{
    std::sort(valueAndWeight.begin(), valueAndWeight.end());
    double total = 0.0;
    for (const auto& [v, w] : valueAndWeight) total += w;
    double sum = 0.0;
    for (const auto& [v, w] : valueAndWeight)
        if ((sum += w) >= q * total) return v;
    return valueAndWeight.back().first;
}

/// Whether every corner of the box projects inside `margin` of the picture's half-size.
bool boxFits(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Camera& camera, const RenderSettings& settings, double margin)
{
    const View view = makeView(camera, settings);
    for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d corner(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z());
        const Eigen::Vector3d p = view.project(corner);
        if (p.z() <= 0 || std::abs(p.x() - view.cx) > margin * view.cx || std::abs(p.y() - view.cy) > margin * view.cy) return false;
    }
    return true;
}

}  // namespace

Camera frameCamera(const std::vector<std::vector<FragmentRef>>& sets, const RenderSettings& settings)
{
    // Per axis, the box that holds all but the outermost 1 % of the voxels on either side, so a
    // few far-flung pieces do not shrink the rest to a speck.
    std::array<std::vector<std::pair<double, double>>, 3> lows, highs;
    for (const auto& set : sets)
        for (const FragmentRef& f : set) {
            openvdb::CoordBBox box;
            double voxels = 0.0;
            withGrid(f.grid, [&](const auto& g) {
                box = g.evalActiveVoxelBoundingBox();
                voxels = double(g.activeVoxelCount());
            });
            Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
            for (int c = 0; c < 8; ++c) {
                const openvdb::Vec3d corner((c & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5), (c & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5),
                                            (c & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5));
                const Eigen::Vector3d w = toEigen(f.transform->indexToWorld(corner));
                lo = lo.cwiseMin(w);
                hi = hi.cwiseMax(w);
            }
            for (int a = 0; a < 3; ++a) {
                lows[a].push_back({lo[a], voxels});
                highs[a].push_back({hi[a], voxels});
            }
        }
    Camera cam;
    if (lows[0].empty()) return cam;
    Eigen::Vector3d lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = weightedQuantile(lows[a], 0.01);
        hi[a] = weightedQuantile(highs[a], 0.99);
    }
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    const Eigen::Vector3d direction = Eigen::Vector3d(-0.55, -1.0, 0.5).normalized();
    cam.targetM = centre;
    // The nearest eye from which the box fills 90 % of the picture's width or height (bisection).
    double near = 1e-3, far = std::max(1.0, 100.0 * (hi - lo).norm());
    for (int i = 0; i < 60; ++i) {
        const double mid = std::sqrt(near * far);
        cam.eyeM = centre + mid * direction;
        (boxFits(lo, hi, cam, settings, 0.9) ? far : near) = mid;
    }
    cam.eyeM = centre + far * direction;
    return cam;
}

namespace {

/// Sky and a chequered ground: one ray per pixel.
void drawBackground(Image& img, std::vector<float>& depth, const View& view, const RenderSettings& settings)
{
    const Eigen::Matrix3d toWorld = view.toCamera.transpose();
    for (int y = 0; y < settings.height; ++y)
        for (int x = 0; x < settings.width; ++x) {
            const Eigen::Vector3d dirCam((x + 0.5 - view.cx) / view.focal, -(y + 0.5 - view.cy) / view.focal, -1.0);
            const Eigen::Vector3d dir = toWorld * dirCam;
            if (dir.z() < -1e-9 && view.eye.z() > settings.groundHeightM) {
                const double t = (settings.groundHeightM - view.eye.z()) / dir.z();
                const Eigen::Vector3d p = view.eye + t * dir;
                const bool odd = (int(std::floor(p.x())) + int(std::floor(p.y()))) & 1;
                const double fade = std::exp(-t / 80.0);
                const uint8_t g = uint8_t((odd ? 150 : 175) * fade + 200 * (1 - fade));
                img.set(x, y, {g, uint8_t(g * 0.97), uint8_t(g * 0.9)});
                depth[size_t(y) * settings.width + x] = float(-(view.toCamera * (p - view.eye)).z());
            } else {
                const double s = std::clamp(dir.normalized().z(), 0.0, 1.0);
                img.set(x, y, {uint8_t(200 - 90 * s), uint8_t(215 - 70 * s), uint8_t(235 - 20 * s)});
            }
        }
}

const int kFaceAxes[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};

/// Face f of voxel ijk as two shaded triangles, unless it faces away from the eye.
void drawVoxelFace(Image& img, std::vector<float>& depth, const View& view, const openvdb::math::Transform& xf, const openvdb::Coord& ijk,
                   int f, const Rgb& base)
{
    const Eigen::Vector3d light = Eigen::Vector3d(-0.4, -0.7, 0.9).normalized();
    // The face's four corners in index space, then in the world.
    const int axis = f / 2;
    const double side = (f & 1) ? 0.5 : -0.5;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    Eigen::Vector3d corners[4];
    for (int k = 0; k < 4; ++k) {
        openvdb::Vec3d p(ijk.x(), ijk.y(), ijk.z());
        p[axis] += side;
        p[u] += (k == 1 || k == 2) ? 0.5 : -0.5;
        p[v] += (k >= 2) ? 0.5 : -0.5;
        corners[k] = toEigen(xf.indexToWorld(p));
    }
    const openvdb::Vec3d outside(ijk.x() + kFaceAxes[f][0], ijk.y() + kFaceAxes[f][1], ijk.z() + kFaceAxes[f][2]);
    const Eigen::Vector3d normal = (toEigen(xf.indexToWorld(outside)) - toEigen(xf.indexToWorld(ijk))).normalized();
    const Eigen::Vector3d faceCentre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
    if (normal.dot(view.eye - faceCentre) <= 0) return;  // back face
    const double shade = 0.35 + 0.65 * std::max(0.0, normal.dot(light));
    const Rgb c{uint8_t(base.r * shade), uint8_t(base.g * shade), uint8_t(base.b * shade)};
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = view.project(corners[k]);
    rasteriseTriangle(img, depth, p[0], p[1], p[2], c);
    rasteriseTriangle(img, depth, p[0], p[2], p[3], c);
}

/// A disc of the charge colour, ringed dark, where the charge is, unless something in front of
/// it hides it: a marker a picture's reader can find at any size.
void drawCharge(Image& img, const std::vector<float>& depth, const View& view, const Eigen::Vector3d& chargeM)
{
    const Eigen::Vector3d p = view.project(chargeM);
    if (p.z() <= 1e-3) return;  // behind the camera
    const double radius = std::max(3.0, img.height() / 90.0), ring = radius + 1.5;
    for (int y = std::max(0, int(p.y() - ring)); y <= std::min(img.height() - 1, int(p.y() + ring)); ++y)
        for (int x = std::max(0, int(p.x() - ring)); x <= std::min(img.width() - 1, int(p.x() + ring)); ++x) {
            const double r = std::hypot(x + 0.5 - p.x(), y + 0.5 - p.y());
            if (r > ring || depth[size_t(y) * img.width() + x] < float(p.z())) continue;
            img.set(x, y, r <= radius ? kChargeColour : Rgb{60, 25, 0});
        }
}

}  // namespace

Image renderFragments(const std::vector<FragmentRef>& fragments, const Camera& camera, const RenderSettings& settings)
{
    Image img(settings.width, settings.height, {0, 0, 0});
    std::vector<float> depth(size_t(settings.width) * settings.height, std::numeric_limits<float>::infinity());
    const View view = makeView(camera, settings);
    drawBackground(img, depth, view, settings);
    // Exposed faces: the neighbour across the face is not in the same fragment.
    for (const FragmentRef& fragment : fragments) withGrid(fragment.grid, [&](const auto& grid) {
        const Rgb base = fragmentColour(fragment.id);
        auto acc = grid.getConstAccessor();
        for (auto it = grid.cbeginValueOn(); it; ++it) {
            if (!it.isVoxelValue()) continue;
            const openvdb::Coord ijk = it.getCoord();
            for (int f = 0; f < 6; ++f)
                if (!acc.isValueOn(ijk + openvdb::Coord(kFaceAxes[f][0], kFaceAxes[f][1], kFaceAxes[f][2])))
                    drawVoxelFace(img, depth, view, *fragment.transform, ijk, f, base);
        }
    });
    for (const Eigen::Vector3d& charge : settings.chargesM) drawCharge(img, depth, view, charge);
    return img;
}

Image contactSheet(const std::vector<Image>& frames, const std::vector<double>& timesS, int columns)
{
    if (frames.empty()) return Image(1, 1);
    const int w = frames[0].width(), h = frames[0].height(), label = 30, gap = 6;
    const int rows = (static_cast<int>(frames.size()) + columns - 1) / columns;
    Image sheet(columns * (w + gap) + gap, rows * (h + label + gap) + gap, {255, 255, 255});
    for (size_t i = 0; i < frames.size(); ++i) {
        const int x0 = gap + int(i % columns) * (w + gap), y0 = gap + int(i / columns) * (h + label + gap);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) sheet.set(x0 + x, y0 + y, frames[i].get(x, y));
        char text[48];
        std::snprintf(text, sizeof text, "t %.3f s", timesS[i]);
        sheet.text(x0 + 4, y0 + h + 8, text, {40, 40, 40});
    }
    return sheet;
}

int writeContactSheet(const std::string& outputDirectory, const std::string& pngPath, int count, const RenderSettings& settings,
                      const std::optional<Camera>& chosenCamera)
{
    const std::vector<std::string> paths = listFramePaths(outputDirectory);
    const int n = std::min<int>(count, static_cast<int>(paths.size()));
    std::vector<FrameGrids> frames;
    for (int i = 0; i < n; ++i) {
        const size_t index = n == 1 ? paths.size() - 1 : size_t(std::lround(double(i) * (paths.size() - 1) / (n - 1)));
        frames.push_back(readFrame(paths[index]));
    }
    const Camera camera = chosenCamera ? *chosenCamera : frameCamera({fragmentsOf(frames.front()), fragmentsOf(frames.back())}, settings);
    std::vector<Image> images;
    std::vector<double> times;
    for (const FrameGrids& f : frames) {
        images.push_back(renderFragments(fragmentsOf(f), camera, settings));
        times.push_back(f.timeS);
    }
    writePng(pngPath, contactSheet(images, times, n <= 4 ? n : 3));
    return n;
}

}  // namespace spall
