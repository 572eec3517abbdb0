#include "predictor/maps.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "plot/png.hpp"
#include "physics/trajectory.hpp"
#include "plot/draw.hpp"

namespace dw::predictor {

using plot::bgr;
using plot::nice_step;
using plot::text;

namespace {

const char* const kAxisLabel[6] = {"f_n [N]", "f_e [N]", "f_d [N]", "m_roll [N m]", "m_pitch [N m]", "m_yaw [N m]"};

std::vector<Outline> outlines_for(const std::string& formation) {
    std::vector<Outline> o{{0, 0, 0.19, true}};
    for (const auto& off : physics::make_formation(formation).offsets) o.push_back({off.x(), off.y(), 0.19, false});
    return o;
}

}  // namespace

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
    const std::string title =
        log::cat(kAxisLabel[r.axis], " on the sufferer: ", r.formation, " at ", fixed(r.altitude_m, 1),
                 " m above it, flying +E at ", fixed(r.speed_mps, 1), " m/s (position of the formation's centre)");
    return render_fields(fields, title, kAxisLabel[r.axis], outlines_for(r.formation), png);
}

void draw_force_line(const std::vector<const ForceModel*>& models, const MapRequest& r, const std::string& png) {
    const int W = 880, H = 440, left = 70, right = 240, top = 50, bottom = 60;
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
            if (std::abs(c[2] - r.altitude_m) > r.band_m || std::abs(c[0]) > 0.1 || std::abs(c[1]) > r.half_width_m)
                continue;
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
    auto X = [&](double e) {
        return left + static_cast<int>(std::lround((e + r.half_width_m) / (2 * r.half_width_m) * pw));
    };
    auto Y = [&](double v) { return top + static_cast<int>(std::lround((hi - v) / (hi - lo) * ph)); };
    cv::rectangle(img, {left, top}, {left + pw, top + ph}, cv::Scalar(40, 40, 40));
    const double step = nice_step(hi - lo);
    for (double v = std::ceil(lo / step) * step; v <= hi; v += step) {
        cv::line(img, {left, Y(v)}, {left + pw, Y(v)}, cv::Scalar(225, 225, 225));
        text(img, fixed(std::abs(v) < 1e-12 ? 0.0 : v, step >= 1 ? 0 : (step >= 0.1 ? 1 : 2)), {left - 6, Y(v) + 4},
             0.4, 2);
    }
    for (double e = -1.0; e <= 1.0 + 1e-9; e += 0.5) {
        cv::line(img, {X(e), top + ph}, {X(e), top + ph + 4}, cv::Scalar(40, 40, 40));
        text(img, fixed(e, 1), {X(e), top + ph + 18}, 0.4, 1);
    }
    text(img, "E of the formation's centre [m] (N = 0, through the stand)", {left + pw / 2, H - 18}, 0.45, 1);
    text(img,
         log::cat(kAxisLabel[r.axis], " along E: ", r.formation, " at ", fixed(r.altitude_m, 1), " m, +E at ",
                  fixed(r.speed_mps, 1), " m/s"),
         {W / 2, 28}, 0.55, 1);
    const cv::Scalar palette[] = {{0, 0, 0}, {200, 120, 0}, {0, 140, 0}, {40, 40, 220}, {160, 0, 160}, {0, 160, 200}};
    for (std::size_t k = 0; k < curves.size(); ++k) {
        std::vector<cv::Point> pts;
        for (int i = 0; i < n; ++i)
            pts.push_back(
                {X(-r.half_width_m + 2 * r.half_width_m * i / (n - 1)), Y(curves[k][static_cast<std::size_t>(i)])});
        cv::polylines(img, pts, false, palette[k % 6], 2, cv::LINE_AA);
        cv::line(img, {left + pw + 15, top + 20 + 22 * static_cast<int>(k)},
                 {left + pw + 40, top + 20 + 22 * static_cast<int>(k)}, palette[k % 6], 2);
        text(img, models[k]->name(), {left + pw + 46, top + 25 + 22 * static_cast<int>(k)}, 0.45);
    }
    if (!points.empty()) {
        for (const auto& p : points)
            cv::circle(img, {X(p[0]), Y(p[1])}, 3, cv::Scalar(80, 80, 80), cv::FILLED, cv::LINE_AA);
        const int ky = top + 25 + 22 * static_cast<int>(curves.size());
        cv::circle(img, {left + pw + 27, ky - 5}, 3, cv::Scalar(80, 80, 80), cv::FILLED);
        text(img, "observed (legs both ways)", {left + pw + 46, ky}, 0.45);
    }
    plot::write_png(img, png);
}

}  // namespace dw::predictor
