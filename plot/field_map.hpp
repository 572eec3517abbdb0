#pragma once
// Field maps drawn headless with OpenCV (PNG): square N-E fields side by side on one symmetric,
// diverging colour scale (blue - white - red) with iso-lines, a colour bar, axes in metres and
// vehicle outlines. Used by the predictor's force maps and the explainer's residual maps.
#include <array>
#include <string>
#include <vector>

namespace dw::plot {

// Values on a square N-E grid centred on the stand; NaN where there is no data.
struct Field {
    std::string title;
    double half_width_m = 1.2;
    int cells = 61;         // per side; cell i at -half_width + i * step
    std::vector<double> v;  // row-major: index = i_n * cells + i_e
    double step() const { return 2 * half_width_m / (cells - 1); }
    double at(int i_n, int i_e) const { return v[static_cast<std::size_t>(i_n * cells + i_e)]; }
};

struct Outline {
    double n = 0, e = 0, radius_m = 0.19;
    bool sufferer = false;
};

struct MapLayout {
    double vmin = 0, vmax = 0;  // the colour scale
    int width = 0, height = 0;
    struct Panel {
        int x = 0, y = 0, size = 0;
    };
    std::vector<Panel> panels;  // one square per field
    double half_width_m = 1.2;
    // The pixel of a point (N, E) in panel p.
    std::array<int, 2> pixel(int p, double n, double e) const;
};

// The diverging colour (B, G, R) of value v on the scale [vmin, vmax] (blue - white - red).
std::array<unsigned char, 3> colour_of(double v, double vmin, double vmax);

// Draws fields side by side on one symmetric colour scale. Throws dw::RuntimeError if the PNG
// cannot be written.
MapLayout render_fields(const std::vector<Field>& fields, const std::string& title, const std::string& unit,
                        const std::vector<Outline>& outlines, const std::string& png);

}  // namespace dw::plot
