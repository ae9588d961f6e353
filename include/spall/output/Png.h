// Minimal raster images written as PNG (libpng), for plots and previews.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace spall {

struct Rgb {
    uint8_t r = 0, g = 0, b = 0;
};

class Image {
public:
    Image(int width, int height, Rgb background = {255, 255, 255});
    int width() const { return mWidth; }
    int height() const { return mHeight; }
    void set(int x, int y, Rgb c)
    {
        if (x >= 0 && y >= 0 && x < mWidth && y < mHeight) mPixels[size_t(y) * mWidth + x] = c;
    }
    Rgb get(int x, int y) const { return mPixels[size_t(y) * mWidth + x]; }
    void line(double x0, double y0, double x1, double y1, Rgb c, int thickness = 1);
    void fillRect(int x0, int y0, int x1, int y1, Rgb c);
    /// Text in a 5x7 pixel font (digits, letters, . - + ( ) / : and space), scaled by `scale`.
    void text(int x, int y, const std::string& s, Rgb c, int scale = 2);
    static int textWidth(const std::string& s, int scale = 2) { return static_cast<int>(s.size()) * 6 * scale; }
    const std::vector<Rgb>& pixels() const { return mPixels; }

private:
    int mWidth, mHeight;
    std::vector<Rgb> mPixels;
};

/// Writes an 8-bit RGB PNG atomically (temporary name, then rename). Throws IoError.
void writePng(const std::string& path, const Image& image);

/// One named line of a plot.
struct PlotSeries {
    std::string name;
    std::vector<double> x, y;
};

/// Linear axes, or logarithmic ones (ticks at powers of ten) for y or for both.
enum class PlotScale { Linear, LogY, LogLog };

/// Lines with axes, ticks, labels and a legend in the corner where it hides least; on a
/// logarithmic axis, points that are not positive are left out.
Image plotSeries(const std::vector<PlotSeries>& series, const std::string& xLabel, const std::string& yLabel, const std::string& title,
                 PlotScale scale, int width = 900, int height = 560);

/// A line plot of y(x) with axes, ticks and labels.
Image plotCurve(const std::vector<double>& x, const std::vector<double>& y, const std::string& xLabel,
                const std::string& yLabel, const std::string& title, int width = 900, int height = 560);

}  // namespace spall
