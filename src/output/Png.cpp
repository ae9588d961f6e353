#include <spall/output/Png.h>

#include <spall/core/AtomicFile.h>

#include <spall/core/Error.h>

#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace spall {

namespace {

/// 5x7 glyphs, one byte per row, bit 4 = leftmost pixel.
const std::map<char, std::array<uint8_t, 7>>& font()
{
    static const std::map<char, std::array<uint8_t, 7>> glyphs = {
        {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},    {'2', {14, 17, 1, 2, 4, 8, 31}},
        {'3', {31, 2, 4, 2, 1, 17, 14}},     {'4', {2, 6, 10, 18, 31, 2, 2}},   {'5', {31, 16, 30, 1, 1, 17, 14}},
        {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},     {'8', {14, 17, 17, 14, 17, 17, 14}},
        {'9', {14, 17, 17, 15, 1, 2, 12}},   {'.', {0, 0, 0, 0, 0, 12, 12}},    {'-', {0, 0, 0, 31, 0, 0, 0}},
        {'+', {0, 4, 4, 31, 4, 4, 0}},       {'(', {2, 4, 8, 8, 8, 4, 2}},      {')', {8, 4, 2, 2, 2, 4, 8}},
        {'/', {1, 1, 2, 4, 8, 16, 16}},      {':', {0, 12, 12, 0, 12, 12, 0}},  {' ', {0, 0, 0, 0, 0, 0, 0}},
        {'a', {0, 0, 14, 1, 15, 17, 15}},    {'b', {16, 16, 22, 25, 17, 17, 30}}, {'c', {0, 0, 14, 16, 16, 17, 14}},
        {'d', {1, 1, 13, 19, 17, 17, 15}},   {'e', {0, 0, 14, 17, 31, 16, 14}}, {'f', {6, 9, 8, 28, 8, 8, 8}},
        {'g', {0, 15, 17, 17, 15, 1, 14}},   {'h', {16, 16, 22, 25, 17, 17, 17}}, {'i', {4, 0, 12, 4, 4, 4, 14}},
        {'k', {16, 16, 18, 20, 24, 20, 18}}, {'l', {12, 4, 4, 4, 4, 4, 14}},    {'m', {0, 0, 26, 21, 21, 17, 17}},
        {'n', {0, 0, 22, 25, 17, 17, 17}},   {'o', {0, 0, 14, 17, 17, 17, 14}}, {'p', {0, 0, 30, 17, 30, 16, 16}},
        {'r', {0, 0, 22, 25, 16, 16, 16}},   {'s', {0, 0, 14, 16, 14, 1, 30}},  {'t', {8, 8, 28, 8, 8, 9, 6}},
        {'u', {0, 0, 17, 17, 17, 19, 13}},   {'v', {0, 0, 17, 17, 17, 10, 4}},  {'w', {0, 0, 17, 17, 21, 21, 10}},
        {'x', {0, 0, 17, 10, 4, 10, 17}},    {'y', {0, 0, 17, 17, 15, 1, 14}},  {'z', {0, 0, 31, 2, 4, 8, 31}},
        {'A', {14, 17, 17, 31, 17, 17, 17}}, {'B', {30, 17, 17, 30, 17, 17, 30}}, {'F', {31, 16, 16, 30, 16, 16, 16}},
        {'G', {14, 17, 16, 23, 17, 17, 15}}, {'K', {17, 18, 20, 24, 20, 18, 17}}, {'P', {30, 17, 17, 30, 16, 16, 16}},
        {'T', {31, 4, 4, 4, 4, 4, 4}},       {'W', {17, 17, 17, 21, 21, 21, 10}}, {'N', {17, 25, 21, 19, 17, 17, 17}},
        {'R', {30, 17, 17, 30, 20, 18, 17}}, {'Z', {31, 1, 2, 4, 8, 16, 31}},
    };
    return glyphs;
}

std::string formatTick(double v)
{
    char buf[32];
    if (v == 0) return "0";
    const double a = std::abs(v);
    if (a >= 1e4 || a < 1e-2)
        std::snprintf(buf, sizeof buf, "%.1e", v);
    else if (a >= 100)
        std::snprintf(buf, sizeof buf, "%.0f", v);
    else
        std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

/// "Nice" tick step near range/target (1, 2 or 5 times a power of ten).
double tickStep(double range, int target)
{
    const double raw = range / target;
    const double p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * p >= raw) return m * p;
    return 10 * p;
}

}  // namespace

Image::Image(int width, int height, Rgb background)
    : mWidth(width), mHeight(height), mPixels(size_t(width) * size_t(height), background)
{
}

void Image::line(double x0, double y0, double x1, double y1, Rgb c, int thickness)
{
    const int steps = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
    for (int i = 0; i <= steps; ++i) {
        const double t = double(i) / steps;
        const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0)));
        const int y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
        for (int dy = 0; dy < thickness; ++dy)
            for (int dx = 0; dx < thickness; ++dx) set(x + dx - thickness / 2, y + dy - thickness / 2, c);
    }
}

void Image::fillRect(int x0, int y0, int x1, int y1, Rgb c)
{
    for (int y = std::max(0, y0); y < std::min(mHeight, y1); ++y)
        for (int x = std::max(0, x0); x < std::min(mWidth, x1); ++x) mPixels[size_t(y) * mWidth + x] = c;
}

void Image::text(int x, int y, const std::string& s, Rgb c, int scale)
{
    const auto& glyphs = font();
    for (size_t i = 0; i < s.size(); ++i) {
        auto it = glyphs.find(s[i]);
        if (it == glyphs.end()) continue;
        for (int row = 0; row < 7; ++row)
            for (int col = 0; col < 5; ++col)
                if (it->second[row] & (16 >> col))
                    fillRect(x + (int(i) * 6 + col) * scale, y + row * scale, x + (int(i) * 6 + col + 1) * scale, y + (row + 1) * scale, c);
    }
}

void writePng(const std::string& path, const Image& image)
{
    writeFileAtomically(path, [&](std::ostream& out) {
        png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
        png_infop info = png ? png_create_info_struct(png) : nullptr;
        if (!png || !info || setjmp(png_jmpbuf(png))) {
            png_destroy_write_struct(&png, &info);
            throw IoError(path + ": PNG encoding failed");
        }
        // libpng writes through these into the stream, which writeFileAtomically checks.
        png_set_write_fn(
            png, &out,
            [](png_structp p, png_bytep data, png_size_t length) {
                static_cast<std::ostream*>(png_get_io_ptr(p))->write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(length));
            },
            [](png_structp p) { static_cast<std::ostream*>(png_get_io_ptr(p))->flush(); });
        png_set_IHDR(png, info, image.width(), image.height(), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                     PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        std::vector<uint8_t> row(size_t(image.width()) * 3);
        for (int y = 0; y < image.height(); ++y) {
            for (int x = 0; x < image.width(); ++x) {
                const Rgb c = image.get(x, y);
                row[3 * x] = c.r;
                row[3 * x + 1] = c.g;
                row[3 * x + 2] = c.b;
            }
            png_write_row(png, row.data());
        }
        png_write_end(png, nullptr);
        png_destroy_write_struct(&png, &info);
    });
}

Image plotCurve(const std::vector<double>& x, const std::vector<double>& y, const std::string& xLabel, const std::string& yLabel,
                const std::string& title, int width, int height)
{
    return plotSeries({{"", x, y}}, xLabel, yLabel, title, PlotScale::Linear, width, height);
}

namespace {

/// Where values land on a plot: the data range (log10 of it on a log axis) onto the pixel box.
struct PlotAxes {
    int left = 0, right = 0, top = 0, bottom = 0;
    bool logX = false, logY = false;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;

    double xValue(double v) const { return logX ? std::log10(v) : v; }
    double yValue(double v) const { return logY ? std::log10(v) : v; }
    /// Points that are not finite (or, on a log axis, not positive) are left out.
    bool usable(double x, double y) const { return std::isfinite(x) && std::isfinite(y) && (!logX || x > 0) && (!logY || y > 0); }
    double px(double v) const { return left + (v - x0) / (x1 - x0) * (right - left); }
    double py(double v) const { return bottom - (v - y0) / (y1 - y0) * (bottom - top); }
};

PlotAxes fitAxes(const std::vector<PlotSeries>& series, PlotScale scale, int width, int height)
{
    PlotAxes axes;
    axes.left = 110, axes.right = width - 30, axes.top = 50, axes.bottom = height - 70;
    axes.logX = scale == PlotScale::LogLog;
    axes.logY = scale != PlotScale::Linear;
    for (const PlotSeries& s : series)
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!axes.usable(s.x[i], s.y[i])) continue;
            axes.x0 = std::min(axes.x0, axes.xValue(s.x[i]));
            axes.x1 = std::max(axes.x1, axes.xValue(s.x[i]));
            axes.y0 = std::min(axes.y0, axes.yValue(s.y[i]));
            axes.y1 = std::max(axes.y1, axes.yValue(s.y[i]));
        }
    if (axes.x0 > axes.x1) axes.x0 = 0, axes.x1 = 1, axes.y0 = 0, axes.y1 = 1;
    if (axes.x1 <= axes.x0) axes.x1 = axes.x0 + 1;
    const double pad = 0.05 * (axes.y1 - axes.y0 > 0 ? axes.y1 - axes.y0 : 1);
    axes.y0 -= pad;
    axes.y1 += pad;
    return axes;
}

const Rgb kAxisColour{60, 60, 60};

void drawGridAndTicks(Image& img, const PlotAxes& a)
{
    const Rgb grid{225, 225, 225};
    const auto tickStepOf = [](bool log, double span, int ticks) { return log ? std::max(1.0, std::ceil(span / ticks)) : tickStep(span, ticks); };
    const auto tickLabel = [](bool log, double v) { return log ? "1e" + formatTick(v) : formatTick(v); };
    const double xs = tickStepOf(a.logX, a.x1 - a.x0, 8), ys = tickStepOf(a.logY, a.y1 - a.y0, 6);
    for (double v = std::ceil(a.x0 / xs) * xs; v <= a.x1 + 1e-12 * xs; v += xs) {
        img.line(a.px(v), a.top, a.px(v), a.bottom, grid);
        const std::string s = tickLabel(a.logX, v);
        img.text(int(a.px(v)) - Image::textWidth(s) / 2, a.bottom + 10, s, kAxisColour);
    }
    for (double v = std::ceil(a.y0 / ys) * ys; v <= a.y1 + 1e-12 * ys; v += ys) {
        img.line(a.left, a.py(v), a.right, a.py(v), grid);
        const std::string s = tickLabel(a.logY, v);
        img.text(a.left - 10 - Image::textWidth(s), int(a.py(v)) - 7, s, kAxisColour);
    }
    if (!a.logY && a.y0 < 0 && a.y1 > 0) img.line(a.left, a.py(0), a.right, a.py(0), kAxisColour);
    img.line(a.left, a.top, a.left, a.bottom, kAxisColour);
    img.line(a.left, a.bottom, a.right, a.bottom, kAxisColour);
}

const Rgb kSeriesColours[] = {{30, 90, 200}, {200, 60, 40}, {40, 150, 60}, {150, 60, 170}, {220, 140, 20}, {20, 150, 160}};

/// Each series as a line (with markers when there are several); returns the pixels it went
/// through, one sample every pixel or so, for the legend to keep clear of.
std::vector<std::pair<double, double>> drawSeries(Image& img, const PlotAxes& a, const std::vector<PlotSeries>& series)
{
    std::vector<std::pair<double, double>> drawn;
    for (size_t k = 0; k < series.size(); ++k) {
        const PlotSeries& s = series[k];
        const Rgb colour = kSeriesColours[k % std::size(kSeriesColours)];
        bool havePrevious = false;
        double previousX = 0, previousY = 0;
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!a.usable(s.x[i], s.y[i])) {
                havePrevious = false;  // a gap, not a line across it
                continue;
            }
            const double cx = a.px(a.xValue(s.x[i])), cy = a.py(a.yValue(s.y[i]));
            if (havePrevious) {
                img.line(previousX, previousY, cx, cy, colour, 2);
                const int steps = 1 + int(std::hypot(cx - previousX, cy - previousY));
                for (int j = 1; j <= steps; ++j) drawn.push_back({previousX + (cx - previousX) * j / steps, previousY + (cy - previousY) * j / steps});
            }
            if (series.size() > 1) img.fillRect(int(cx) - 3, int(cy) - 3, int(cx) + 3, int(cy) + 3, colour);
            drawn.push_back({cx, cy});
            havePrevious = true;
            previousX = cx;
            previousY = cy;
        }
    }
    return drawn;
}

/// The series' names on a white box in the corner of the plot that hides least of the lines.
void drawLegend(Image& img, const PlotAxes& a, const std::vector<PlotSeries>& series, const std::vector<std::pair<double, double>>& drawn)
{
    int rows = 0, widest = 0;
    for (const PlotSeries& s : series) {
        rows += !s.name.empty();
        widest = std::max(widest, Image::textWidth(s.name));
    }
    if (rows == 0) return;
    const int boxWidth = widest + 40, boxHeight = 20 * rows + 8, gap = 8;
    const int xs[] = {a.right - gap - boxWidth, a.left + gap}, ys[] = {a.top + gap, a.bottom - gap - boxHeight};
    int bestX = xs[0], bestY = ys[0];
    size_t leastHidden = SIZE_MAX;
    for (const int y : ys)  // upper right first, then upper left, lower right, lower left
        for (const int x : xs) {
            const size_t hidden = size_t(std::count_if(drawn.begin(), drawn.end(), [&](const auto& p) {
                return p.first >= x && p.first <= x + boxWidth && p.second >= y && p.second <= y + boxHeight;
            }));
            if (hidden < leastHidden) leastHidden = hidden, bestX = x, bestY = y;
        }
    img.fillRect(bestX, bestY, bestX + boxWidth, bestY + boxHeight, {255, 255, 255});
    img.line(bestX, bestY, bestX + boxWidth, bestY, {200, 200, 200});
    img.line(bestX, bestY + boxHeight, bestX + boxWidth, bestY + boxHeight, {200, 200, 200});
    img.line(bestX, bestY, bestX, bestY + boxHeight, {200, 200, 200});
    img.line(bestX + boxWidth, bestY, bestX + boxWidth, bestY + boxHeight, {200, 200, 200});
    int row = 0;
    for (size_t k = 0; k < series.size(); ++k) {
        if (series[k].name.empty()) continue;
        const int ly = bestY + 6 + 20 * row++;
        img.fillRect(bestX + 8, ly + 2, bestX + 22, ly + 12, kSeriesColours[k % std::size(kSeriesColours)]);
        img.text(bestX + 30, ly, series[k].name, kAxisColour);
    }
}

}  // namespace

Image plotSeries(const std::vector<PlotSeries>& series, const std::string& xLabel, const std::string& yLabel, const std::string& title,
                 PlotScale scale, int width, int height)
{
    Image img(width, height);
    const PlotAxes axes = fitAxes(series, scale, width, height);
    drawGridAndTicks(img, axes);
    drawLegend(img, axes, series, drawSeries(img, axes, series));
    img.text((axes.left + axes.right - Image::textWidth(xLabel)) / 2, height - 35, xLabel, kAxisColour);
    img.text(10, 15, yLabel, kAxisColour);
    img.text((axes.left + axes.right - Image::textWidth(title)) / 2, 15, title, kAxisColour);
    return img;
}

}  // namespace spall
