#include "plot/field_map.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "plot/draw.hpp"
#include "plot/png.hpp"

namespace dw::plot {

std::array<unsigned char, 3> colour_of(double v, double vmin, double vmax) {
    if (std::isnan(v)) return {200, 200, 200};
    const double mid = 0.5 * (vmin + vmax), half = 0.5 * (vmax - vmin);
    const double x = std::clamp(half > 0 ? (v - mid) / half : 0.0, -1.0, 1.0);
    auto u8 = [](double c) { return static_cast<unsigned char>(std::lround(std::clamp(c, 0.0, 255.0))); };
    // white at 0; towards (B,G,R) = (180, 40, 20) (blue) below and (30, 30, 200) (red) above
    if (x >= 0) return {u8(255 - x * 225), u8(255 - x * 225), u8(255 - x * 55)};
    const double a = -x;
    return {u8(255 - a * 75), u8(255 - a * 215), u8(255 - a * 235)};
}

std::array<int, 2> MapLayout::pixel(int p, double n, double e) const {
    const auto& q = panels[static_cast<std::size_t>(p)];
    const double s = q.size / (2 * half_width_m);
    return {q.x + static_cast<int>(std::lround((e + half_width_m) * s)),
            q.y + static_cast<int>(std::lround((half_width_m - n) * s))};
}

MapLayout render_fields(const std::vector<Field>& fields, const std::string& title, const std::string& unit,
                        const std::vector<Outline>& outlines, const std::string& png) {
    MapLayout L;
    if (fields.empty()) throw RuntimeError("render_fields: nothing to draw");
    L.half_width_m = fields.front().half_width_m;
    double m = 0;
    for (const auto& f : fields)
        for (double v : f.v)
            if (std::isfinite(v)) m = std::max(m, std::abs(v));
    if (m == 0) m = 1;
    L.vmin = -m;
    L.vmax = m;
    const int size = 300, gap = 70, left = 60, top = 60, bar = 90;
    L.width = left + static_cast<int>(fields.size()) * (size + gap) + bar;
    L.height = top + size + 70;
    cv::Mat img(L.height, L.width, CV_8UC3, cv::Scalar(255, 255, 255));
    text(img, title, {L.width / 2, 24}, 0.6, 1, 1);
    for (std::size_t p = 0; p < fields.size(); ++p) {
        const auto& f = fields[p];
        L.panels.push_back({left + static_cast<int>(p) * (size + gap), top, size});
        const auto& q = L.panels.back();
        cv::Mat values(size, size, CV_64F);
        for (int py = 0; py < size; ++py)
            for (int px = 0; px < size; ++px) {
                const double e = -f.half_width_m + (px + 0.5) * 2 * f.half_width_m / size;
                const double n = f.half_width_m - (py + 0.5) * 2 * f.half_width_m / size;
                const int ie = static_cast<int>(std::lround((e + f.half_width_m) / f.step()));
                const int in = static_cast<int>(std::lround((n + f.half_width_m) / f.step()));
                const double v = (ie < 0 || in < 0 || ie >= f.cells || in >= f.cells) ? NAN : f.at(in, ie);
                values.at<double>(py, px) = v;
                const auto c = colour_of(v, L.vmin, L.vmax);
                img.at<cv::Vec3b>(q.y + py, q.x + px) = cv::Vec3b(c[0], c[1], c[2]);
            }
        // Iso-lines at ±25, 50, 75 % of the scale.
        for (double level : {-0.75, -0.5, -0.25, 0.25, 0.5, 0.75}) {
            cv::Mat mask = level > 0 ? (values > level * m) : (values < level * m);
            std::vector<std::vector<cv::Point>> contours;
            cv::findContours(mask, contours, cv::RETR_LIST, cv::CHAIN_APPROX_SIMPLE, cv::Point(q.x, q.y));
            cv::drawContours(img, contours, -1, cv::Scalar(90, 90, 90), 1, cv::LINE_AA);
        }
        for (const auto& o : outlines) {
            const auto c = L.pixel(static_cast<int>(p), o.n, o.e);
            const int r = static_cast<int>(std::lround(o.radius_m * size / (2 * L.half_width_m)));
            cv::circle(img, {c[0], c[1]}, r, o.sufferer ? cv::Scalar(0, 0, 0) : cv::Scalar(0, 140, 0),
                       o.sufferer ? 2 : 1, cv::LINE_AA);
        }
        cv::rectangle(img, {q.x - 1, q.y - 1}, {q.x + size, q.y + size}, cv::Scalar(40, 40, 40), 1);
        text(img, f.title, {q.x + size / 2, q.y - 10}, 0.5, 1);
        // Axes: E to the right, N up, ticks every 0.5 m.
        for (double t = -std::floor(L.half_width_m * 2) / 2; t <= L.half_width_m + 1e-9; t += 0.5) {
            const auto px = L.pixel(static_cast<int>(p), -L.half_width_m, t);
            cv::line(img, {px[0], q.y + size}, {px[0], q.y + size + 4}, cv::Scalar(40, 40, 40));
            text(img, fixed(t, 1), {px[0], q.y + size + 18}, 0.38, 1);
            const auto py = L.pixel(static_cast<int>(p), t, -L.half_width_m);
            cv::line(img, {q.x - 4, py[1]}, {q.x, py[1]}, cv::Scalar(40, 40, 40));
            text(img, fixed(t, 1), {q.x - 6, py[1] + 4}, 0.38, 2);
        }
        text(img, "E [m]", {q.x + size / 2, q.y + size + 36}, 0.42, 1);
        text(img, "N [m]", {q.x - 30, q.y - 10}, 0.42, 1);
    }
    // Colour bar.
    const int bx = L.width - bar + 15, bw = 18;
    for (int py = 0; py < size; ++py) {
        const double v = L.vmax - (L.vmax - L.vmin) * py / (size - 1);
        cv::line(img, {bx, top + py}, {bx + bw, top + py}, bgr(colour_of(v, L.vmin, L.vmax)));
    }
    cv::rectangle(img, {bx - 1, top - 1}, {bx + bw, top + size}, cv::Scalar(40, 40, 40));
    const double step = nice_step(L.vmax - L.vmin);
    const int prec = step >= 1 ? 0 : (step >= 0.1 ? 1 : (step >= 0.01 ? 2 : 3));
    for (double v = std::ceil(L.vmin / step) * step; v <= L.vmax + 1e-12; v += step) {
        const int py = top + static_cast<int>(std::lround((L.vmax - v) / (L.vmax - L.vmin) * (size - 1)));
        cv::line(img, {bx + bw, py}, {bx + bw + 4, py}, cv::Scalar(40, 40, 40));
        text(img, fixed(std::abs(v) < 1e-12 ? 0.0 : v, prec), {bx + bw + 6, py + 4}, 0.38);
    }
    text(img, unit, {bx + bw / 2, top - 10}, 0.42, 1);
    write_png(img, png);
    return L;
}

}  // namespace dw::plot
