#pragma once
// Charts drawn headless with OpenCV (PNG): lines of y against x (several series, a legend,
// vertical marks), and binned heat maps of a value over two coordinates on the diverging colour
// scale of the field maps. Used by the explainer's reports on flights without legs.
#include <array>
#include <string>
#include <vector>

namespace dw::plot {

struct Series {
    std::string label;
    std::vector<double> x, y;  // NaN y: a break in the line
    std::array<unsigned char, 3> bgr{0, 0, 0};
};

struct Chart {
    std::string title, x_label, y_label;
    std::vector<Series> series;
    std::vector<double> marks;  // vertical lines at these x (e.g. closest approaches)
};

// Throws dw::RuntimeError if the PNG cannot be written.
void render_chart(const Chart& chart, const std::string& png, int width = 1400, int height = 460);

// A value averaged over cells of (x, y); NaN where no sample fell.
struct Heat {
    std::string title;
    double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    int nx = 10, ny = 10;
    std::vector<double> v;  // row-major from y0: index = iy * nx + ix
};
// Bins samples (x, y, value) into a Heat (samples outside the range are left out; a cell needs
// min_count samples).
Heat bin_heat(const std::string& title, const std::vector<std::array<double, 3>>& samples, double x0, double x1,
              double y0, double y1, int nx, int ny, int min_count = 3);
// Heats side by side on one symmetric colour scale.
void render_heats(const std::vector<Heat>& heats, const std::string& title, const std::string& x_label,
                  const std::string& y_label, const std::string& unit, const std::string& png);

}  // namespace dw::plot
