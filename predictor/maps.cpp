#include "predictor/maps.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "physics/trajectory.hpp"

namespace dw::predictor {

namespace {

const char* const kAxisLabel[6] = {"f_n [N]", "f_e [N]", "f_d [N]", "m_roll [N m]", "m_pitch [N m]", "m_yaw [N m]"};

std::string num(double v, int precision) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(precision) << v;
    return s.str();
}

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, int align = 0, int thickness = 1) {
    int base = 0;
    const auto size = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &base);
    if (align == 1) at.x -= size.width / 2;   // centred
    if (align == 2) at.x -= size.width;       // right-aligned
    cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(20, 20, 20), thickness, cv::LINE_AA);
}

cv::Scalar bgr(const std::array<unsigned char, 3>& c) { return {double(c[0]), double(c[1]), double(c[2])}; }

double nice_step(double range) {
    const double raw = range / 5;
    const double p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * p >= raw) return m * p;
    return 10 * p;
}

std::vector<Outline> outlines_for(const std::string& formation) {
    std::vector<Outline> o{{0, 0, 0.19, true}};
    for (const auto& off : physics::make_formation(formation).offsets) o.push_back({off.x(), off.y(), 0.19, false});
    return o;
}

}  // namespace

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
    return {q.x + static_cast<int>(std::lround((e + half_width_m) * s)), q.y + static_cast<int>(std::lround((half_width_m - n) * s))};
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
            cv::circle(img, {c[0], c[1]}, r, o.sufferer ? cv::Scalar(0, 0, 0) : cv::Scalar(0, 140, 0), o.sufferer ? 2 : 1, cv::LINE_AA);
        }
        cv::rectangle(img, {q.x - 1, q.y - 1}, {q.x + size, q.y + size}, cv::Scalar(40, 40, 40), 1);
        text(img, f.title, {q.x + size / 2, q.y - 10}, 0.5, 1);
        // Axes: E to the right, N up, ticks every 0.5 m.
        for (double t = -std::floor(L.half_width_m * 2) / 2; t <= L.half_width_m + 1e-9; t += 0.5) {
            const auto px = L.pixel(static_cast<int>(p), -L.half_width_m, t);
            cv::line(img, {px[0], q.y + size}, {px[0], q.y + size + 4}, cv::Scalar(40, 40, 40));
            text(img, num(t, 1), {px[0], q.y + size + 18}, 0.38, 1);
            const auto py = L.pixel(static_cast<int>(p), t, -L.half_width_m);
            cv::line(img, {q.x - 4, py[1]}, {q.x, py[1]}, cv::Scalar(40, 40, 40));
            text(img, num(t, 1), {q.x - 6, py[1] + 4}, 0.38, 2);
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
        text(img, num(std::abs(v) < 1e-12 ? 0.0 : v, prec), {bx + bw + 6, py + 4}, 0.38);
    }
    text(img, unit, {bx + bw / 2, top - 10}, 0.42, 1);
    if (!cv::imwrite(png, img)) throw RuntimeError(log::cat(png, ": cannot write the PNG"));
    return L;
}

namespace {

std::vector<RelState> neighbours_at(const MapRequest& r, double n, double e) {
    std::vector<RelState> x;
    for (const auto& off : physics::make_formation(r.formation).offsets)
        x.push_back({n + off.x(), e + off.y(), -r.altitude_m + off.z(), 0, r.speed_mps, 0});
    return x;
}

}  // namespace

Field model_field(const ForceModel& model, const MapRequest& r) {
    Field f{model.name(), r.half_width_m, r.cells, {}};
    f.v.resize(static_cast<std::size_t>(r.cells * r.cells));
    for (int i = 0; i < r.cells; ++i)
        for (int j = 0; j < r.cells; ++j) {
            const auto x = neighbours_at(r, -r.half_width_m + i * f.step(), -r.half_width_m + j * f.step());
            f.v[static_cast<std::size_t>(i * r.cells + j)] = model.predict(x)[static_cast<std::size_t>(r.axis)];
        }
    return f;
}

Field observed_field(const Dataset& d, const MapRequest& r, double cell_m) {
    Field f{"observed", r.half_width_m, static_cast<int>(std::lround(2 * r.half_width_m / cell_m)) + 1, {}};
    const auto cells = static_cast<std::size_t>(f.cells * f.cells);
    std::vector<double> sum(cells, 0.0), count(cells, 0.0);
    for (const auto& s : d.samples) {
        if (s.k == 0 || s.leg < 0) continue;
        const auto c = s.reference();
        if (std::abs(c[2] - r.altitude_m) > r.band_m) continue;
        const int in = static_cast<int>(std::lround((c[0] + r.half_width_m) / f.step()));
        const int ie = static_cast<int>(std::lround((c[1] + r.half_width_m) / f.step()));
        if (in < 0 || ie < 0 || in >= f.cells || ie >= f.cells) continue;
        sum[static_cast<std::size_t>(in * f.cells + ie)] += s.y[static_cast<std::size_t>(r.axis)];
        count[static_cast<std::size_t>(in * f.cells + ie)] += 1;
    }
    f.v.resize(cells);
    for (std::size_t i = 0; i < cells; ++i) f.v[i] = count[i] > 0 ? sum[i] / count[i] : NAN;
    return f;
}

MapLayout draw_force_map(const std::vector<const ForceModel*>& models, const MapRequest& r, const std::string& png) {
    std::vector<Field> fields;
    if (r.observed) fields.push_back(observed_field(*r.observed, r));
    for (const auto* m : models) fields.push_back(model_field(*m, r));
    const std::string title = log::cat(kAxisLabel[r.axis], " on the sufferer: ", r.formation, " at ", num(r.altitude_m, 1),
                                       " m above it, flying +E at ", num(r.speed_mps, 1), " m/s (position of the formation's centre)");
    return render_fields(fields, title, kAxisLabel[r.axis], outlines_for(r.formation), png);
}

void draw_force_line(const std::vector<const ForceModel*>& models, const MapRequest& r, const std::string& png) {
    const int W = 820, H = 440, left = 70, right = 180, top = 50, bottom = 60;
    const int pw = W - left - right, ph = H - top - bottom;
    const int n = 241;
    std::vector<std::vector<double>> curves;
    double lo = 0, hi = 0;
    for (const auto* m : models) {
        std::vector<double> c;
        for (int i = 0; i < n; ++i) {
            const double e = -r.half_width_m + 2 * r.half_width_m * i / (n - 1);
            c.push_back(m->predict(neighbours_at(r, 0.0, e))[static_cast<std::size_t>(r.axis)]);
            lo = std::min(lo, c.back());
            hi = std::max(hi, c.back());
        }
        curves.push_back(std::move(c));
    }
    std::vector<std::array<double, 2>> points;  // observed: samples on legs within 0.1 m of N = 0, binned by 5 cm
    if (r.observed) {
        std::vector<double> sum(49, 0), cnt(49, 0);
        for (const auto& s : r.observed->samples) {
            if (s.k == 0 || s.leg < 0) continue;
            const auto c = s.reference();
            if (std::abs(c[2] - r.altitude_m) > r.band_m || std::abs(c[0]) > 0.1 || std::abs(c[1]) > r.half_width_m) continue;
            const auto b = static_cast<std::size_t>(std::lround((c[1] + r.half_width_m) / (2 * r.half_width_m) * 48));
            sum[b] += s.y[static_cast<std::size_t>(r.axis)];
            cnt[b] += 1;
        }
        for (std::size_t b = 0; b < sum.size(); ++b)
            if (cnt[b] > 0) {
                points.push_back({-r.half_width_m + 2 * r.half_width_m * static_cast<double>(b) / 48, sum[b] / cnt[b]});
                lo = std::min(lo, points.back()[1]);
                hi = std::max(hi, points.back()[1]);
            }
    }
    const double pad = 0.08 * std::max(hi - lo, 1e-3);
    lo -= pad;
    hi += pad;
    cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
    auto X = [&](double e) { return left + static_cast<int>(std::lround((e + r.half_width_m) / (2 * r.half_width_m) * pw)); };
    auto Y = [&](double v) { return top + static_cast<int>(std::lround((hi - v) / (hi - lo) * ph)); };
    cv::rectangle(img, {left, top}, {left + pw, top + ph}, cv::Scalar(40, 40, 40));
    const double step = nice_step(hi - lo);
    for (double v = std::ceil(lo / step) * step; v <= hi; v += step) {
        cv::line(img, {left, Y(v)}, {left + pw, Y(v)}, cv::Scalar(225, 225, 225));
        text(img, num(std::abs(v) < 1e-12 ? 0.0 : v, step >= 1 ? 0 : (step >= 0.1 ? 1 : 2)), {left - 6, Y(v) + 4}, 0.4, 2);
    }
    for (double e = -1.0; e <= 1.0 + 1e-9; e += 0.5) {
        cv::line(img, {X(e), top + ph}, {X(e), top + ph + 4}, cv::Scalar(40, 40, 40));
        text(img, num(e, 1), {X(e), top + ph + 18}, 0.4, 1);
    }
    text(img, "E of the formation's centre [m] (N = 0, through the stand)", {left + pw / 2, H - 18}, 0.45, 1);
    text(img, log::cat(kAxisLabel[r.axis], " along E: ", r.formation, " at ", num(r.altitude_m, 1), " m, +E at ",
                       num(r.speed_mps, 1), " m/s"), {W / 2, 28}, 0.55, 1);
    const cv::Scalar palette[] = {{0, 0, 0}, {200, 120, 0}, {0, 140, 0}, {40, 40, 220}, {160, 0, 160}, {0, 160, 200}};
    for (std::size_t k = 0; k < curves.size(); ++k) {
        std::vector<cv::Point> pts;
        for (int i = 0; i < n; ++i) pts.push_back({X(-r.half_width_m + 2 * r.half_width_m * i / (n - 1)), Y(curves[k][static_cast<std::size_t>(i)])});
        cv::polylines(img, pts, false, palette[k % 6], 2, cv::LINE_AA);
        cv::line(img, {left + pw + 15, top + 20 + 22 * static_cast<int>(k)}, {left + pw + 40, top + 20 + 22 * static_cast<int>(k)}, palette[k % 6], 2);
        text(img, models[k]->name(), {left + pw + 46, top + 25 + 22 * static_cast<int>(k)}, 0.45);
    }
    if (!points.empty()) {
        for (const auto& p : points) cv::circle(img, {X(p[0]), Y(p[1])}, 3, cv::Scalar(80, 80, 80), cv::FILLED, cv::LINE_AA);
        const int ky = top + 25 + 22 * static_cast<int>(curves.size());
        cv::circle(img, {left + pw + 27, ky - 5}, 3, cv::Scalar(80, 80, 80), cv::FILLED);
        text(img, "observed (legs both ways)", {left + pw + 46, ky}, 0.45);
    }
    if (!cv::imwrite(png, img)) throw RuntimeError(log::cat(png, ": cannot write the PNG"));
}

}  // namespace dw::predictor
