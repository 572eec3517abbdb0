#include "plot/chart.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "plot/draw.hpp"
#include "plot/field_map.hpp"
#include "plot/png.hpp"

namespace dw::plot {

namespace {

struct Frame {  // the plotting area and its data ranges
    cv::Rect area;
    double x0, x1, y0, y1;
    cv::Point at(double x, double y) const {
        return {area.x + static_cast<int>(std::lround((x - x0) / (x1 - x0) * area.width)),
                area.y + area.height - static_cast<int>(std::lround((y - y0) / (y1 - y0) * area.height))};
    }
};

void axes(cv::Mat& img, const Frame& f, const std::string& x_label, const std::string& y_label) {
    cv::rectangle(img, f.area, cv::Scalar(60, 60, 60));
    const double xs = nice_step(f.x1 - f.x0), ys = nice_step(f.y1 - f.y0);
    for (double x = std::ceil(f.x0 / xs) * xs; x <= f.x1 + 1e-9; x += xs) {
        const auto p = f.at(x, f.y0);
        cv::line(img, p, {p.x, p.y + 5}, cv::Scalar(60, 60, 60));
        text(img, fixed(x, xs < 1 ? (xs < 0.1 ? 2 : 1) : 0), {p.x, p.y + 20}, 0.4, 1);
    }
    for (double y = std::ceil(f.y0 / ys) * ys; y <= f.y1 + 1e-9; y += ys) {
        const auto p = f.at(f.x0, y);
        cv::line(img, p, {p.x - 5, p.y}, cv::Scalar(60, 60, 60));
        text(img, fixed(y, ys < 1 ? (ys < 0.01 ? 3 : 2) : 0), {p.x - 8, p.y + 4}, 0.4, 2);
    }
    text(img, x_label, {f.area.x + f.area.width / 2, f.area.y + f.area.height + 40}, 0.45, 1);
    text(img, y_label, {f.area.x, f.area.y - 8}, 0.45, 0);
}

}  // namespace

void render_chart(const Chart& c, const std::string& png, int width, int height) {
    cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const auto& s : c.series)
        for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
            if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
            x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]), y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
        }
    if (!(x1 > x0)) x0 = 0, x1 = 1;
    if (!(y1 > y0)) y0 -= 1, y1 += 1;
    const double pad = 0.05 * (y1 - y0);
    const Frame f{cv::Rect(80, 50, width - 110, height - 110), x0, x1, y0 - pad, y1 + pad};
    text(img, c.title, {width / 2, 22}, 0.55, 1);
    for (double m : c.marks) {
        if (m < x0 || m > x1) continue;
        cv::line(img, f.at(m, f.y0), f.at(m, f.y1), cv::Scalar(200, 200, 200));
    }
    if (f.y0 < 0 && f.y1 > 0) cv::line(img, f.at(x0, 0), f.at(x1, 0), cv::Scalar(170, 170, 170));
    for (const auto& s : c.series) {
        const cv::Scalar col = bgr(s.bgr);
        for (std::size_t i = 1; i < s.x.size() && i < s.y.size(); ++i) {
            if (!std::isfinite(s.y[i]) || !std::isfinite(s.y[i - 1])) continue;
            cv::line(img, f.at(s.x[i - 1], s.y[i - 1]), f.at(s.x[i], s.y[i]), col, 1, cv::LINE_AA);
        }
    }
    for (std::size_t k = 0; k < c.series.size(); ++k) {  // legend, top right
        const cv::Point p{width - 260, 70 + 18 * static_cast<int>(k)};
        cv::line(img, p, {p.x + 25, p.y}, bgr(c.series[k].bgr), 2);
        text(img, c.series[k].label, {p.x + 32, p.y + 4}, 0.42);
    }
    axes(img, f, c.x_label, c.y_label);
    write_png(img, png);
}

Heat bin_heat(const std::string& title, const std::vector<std::array<double, 3>>& samples, double x0, double x1,
              double y0, double y1, int nx, int ny, int min_count) {
    Heat h{title, x0, x1, y0, y1, nx, ny, {}};
    std::vector<double> sum(static_cast<std::size_t>(nx * ny), 0), n(sum.size(), 0);
    for (const auto& [x, y, v] : samples) {
        const int ix = static_cast<int>(std::floor((x - x0) / (x1 - x0) * nx)),
                  iy = static_cast<int>(std::floor((y - y0) / (y1 - y0) * ny));
        if (ix < 0 || iy < 0 || ix >= nx || iy >= ny || !std::isfinite(v)) continue;
        sum[static_cast<std::size_t>(iy * nx + ix)] += v;
        n[static_cast<std::size_t>(iy * nx + ix)] += 1;
    }
    h.v.resize(sum.size());
    for (std::size_t k = 0; k < sum.size(); ++k) h.v[k] = n[k] >= min_count ? sum[k] / n[k] : NAN;
    return h;
}

void render_heats(const std::vector<Heat>& heats, const std::string& title, const std::string& x_label,
                  const std::string& y_label, const std::string& unit, const std::string& png) {
    constexpr int panel = 380, gap = 90, top = 60, bar = 90;
    const int width = gap + static_cast<int>(heats.size()) * (panel + gap) + bar, height = top + panel + 70;
    cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double vmax = 0;
    for (const auto& h : heats)
        for (double v : h.v)
            if (std::isfinite(v)) vmax = std::max(vmax, std::abs(v));
    if (vmax <= 0) vmax = 1;
    text(img, title, {width / 2, 22}, 0.5, 1);
    for (std::size_t k = 0; k < heats.size(); ++k) {
        const auto& h = heats[k];
        const Frame f{cv::Rect(gap + static_cast<int>(k) * (panel + gap), top, panel, panel), h.x0, h.x1, h.y0, h.y1};
        for (int iy = 0; iy < h.ny; ++iy)
            for (int ix = 0; ix < h.nx; ++ix) {
                const double v = h.v[static_cast<std::size_t>(iy * h.nx + ix)];
                const auto a = f.at(h.x0 + (h.x1 - h.x0) * ix / h.nx, h.y0 + (h.y1 - h.y0) * (iy + 1) / h.ny);
                const auto b = f.at(h.x0 + (h.x1 - h.x0) * (ix + 1) / h.nx, h.y0 + (h.y1 - h.y0) * iy / h.ny);
                const cv::Scalar col = std::isfinite(v) ? bgr(colour_of(v, -vmax, vmax)) : cv::Scalar(235, 235, 235);
                cv::rectangle(img, cv::Rect(a, b), col, cv::FILLED);
            }
        text(img, h.title, {f.area.x + panel / 2, top - 24}, 0.45, 1);
        axes(img, f, x_label, y_label);
    }
    const int bx = width - bar + 20;  // the colour bar
    for (int y = 0; y < panel; ++y)
        cv::line(img, {bx, top + y}, {bx + 18, top + y}, bgr(colour_of(vmax - 2 * vmax * y / panel, -vmax, vmax)));
    text(img, fixed(vmax, 3), {bx, top - 6}, 0.4);
    text(img, fixed(-vmax, 3), {bx, top + panel + 16}, 0.4);
    text(img, unit, {bx, top + panel + 34}, 0.4);
    write_png(img, png);
}

}  // namespace dw::plot
