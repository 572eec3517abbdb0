#include "swarm_planner/picture.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "plot/png.hpp"

namespace dw::planner {
namespace {

constexpr int kScale = 110;  // pixels per metre
constexpr int kMargin = 50;

struct View {
    cv::Rect area;
    double x_min, x_max, y_min, y_max;  // metres: horizontal and vertical axes of the view
    cv::Point px(double x, double y) const {
        return {area.x + static_cast<int>((x - x_min) * kScale),
                area.y + area.height - static_cast<int>((y - y_min) * kScale)};
    }
};

cv::Scalar altitude_colour(double alt, double max_alt) {
    const double a = std::clamp(alt / std::max(max_alt, 1e-6), 0.0, 1.0);
    return {255 * (1 - a), 80, 255 * a};  // blue (low) to red (high), BGR
}

void axes(cv::Mat& img, const View& v, const std::string& title, const std::string& xlabel, const std::string& ylabel) {
    cv::rectangle(img, v.area, {0, 0, 0}, 1);
    for (double x = std::ceil(v.x_min); x <= v.x_max; x += 1) {
        cv::line(img, v.px(x, v.y_min), v.px(x, v.y_min) + cv::Point(0, 5), {0, 0, 0});
        cv::putText(img, log::cat(static_cast<int>(x)), v.px(x, v.y_min) + cv::Point(-5, 20), cv::FONT_HERSHEY_SIMPLEX,
                    0.4, {0, 0, 0});
    }
    for (double y = std::ceil(v.y_min); y <= v.y_max; y += 1) {
        cv::line(img, v.px(v.x_min, y), v.px(v.x_min, y) + cv::Point(-5, 0), {0, 0, 0});
        cv::putText(img, log::cat(static_cast<int>(y)), v.px(v.x_min, y) + cv::Point(-25, 4), cv::FONT_HERSHEY_SIMPLEX,
                    0.4, {0, 0, 0});
    }
    cv::putText(img, title, {v.area.x, v.area.y - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0}, 1);
    cv::putText(img, xlabel, {v.area.x + v.area.width - 60, v.area.y + v.area.height + 38}, cv::FONT_HERSHEY_SIMPLEX,
                0.45, {0, 0, 0});
    cv::putText(img, ylabel, {v.area.x - 45, v.area.y - 12 + 0}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
}

}  // namespace

void draw_plan(const Plan& p, const std::string& png_path) {
    const auto& f = p.options.fence;
    const double stand = p.options.grid.stand_height_m;
    double max_alt = 0;
    for (double a : p.options.grid.altitudes_m) max_alt = std::max(max_alt, a);
    const int top_w = static_cast<int>((f.e_max - f.e_min) * kScale),
              top_h = static_cast<int>((f.n_max - f.n_min) * kScale);
    const int side_h = static_cast<int>((f.d_max - f.d_min) * kScale);
    cv::Mat img(kMargin * 3 + top_h + side_h + 30, kMargin * 2 + top_w, CV_8UC3, cv::Scalar(255, 255, 255));
    const View top{{kMargin, kMargin, top_w, top_h}, f.e_min, f.e_max, f.n_min, f.n_max};
    const View side{{kMargin, kMargin * 2 + top_h + 10, top_w, side_h}, f.e_min, f.e_max, -f.d_max, -f.d_min};
    axes(img, top,
         log::cat("top view: ", p.formation.name, " K=", p.vehicles.size(), ", ", p.reference.legs().size(), " legs, ",
                  static_cast<int>(p.duration_s()), " s"),
         "E [m]", "N [m]");
    axes(img, side, "side view (height above the floor)", "E [m]", "h [m]");
    const double hw = p.options.grid.half_width_m;
    cv::rectangle(img, top.px(-hw, hw), top.px(hw, -hw), {0, 160, 0}, 2);                   // the measured square
    cv::rectangle(img, side.px(-hw, stand + max_alt), side.px(hw, stand), {0, 160, 0}, 2);  // the measured volume
    // The reference path (transitions included), thin and grey.
    cv::Point last_top, last_side;
    for (double t = 0; t <= p.duration_s(); t += 0.05) {
        const auto x = p.reference.at(t).position;
        const cv::Point a = top.px(x.y(), x.x()), b = side.px(x.y(), -x.z());
        if (t > 0) {
            cv::line(img, last_top, a, {190, 190, 190}, 1);
            cv::line(img, last_side, b, {190, 190, 190}, 1);
        }
        last_top = a;
        last_side = b;
    }
    // Each vehicle's measured segments, coloured by altitude.
    for (const auto& leg : p.reference.legs()) {
        const cv::Scalar c = altitude_colour(leg.altitude_m, max_alt);
        for (std::size_t v = 0; v < p.vehicles.size(); ++v) {
            const auto a = p.setpoint(v, leg.t_start).position, b = p.setpoint(v, leg.t_end).position;
            cv::line(img, top.px(a.y(), a.x()), top.px(b.y(), b.x()), c, 2);
            cv::line(img, side.px(a.y(), -a.z()), side.px(b.y(), -b.z()), c, 2);
        }
    }
    // The stand and the sufferer.
    cv::circle(img, top.px(0, 0), static_cast<int>(0.15 * kScale), {0, 0, 0}, 2);
    cv::line(img, side.px(0, 0), side.px(0, stand), {0, 0, 0}, 3);
    cv::rectangle(img, side.px(-0.15, stand + 0.05), side.px(0.15, stand), {0, 0, 0}, cv::FILLED);
    cv::putText(img, "stand", top.px(0.2, -0.25), cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
    int y = img.rows - 15;
    for (std::size_t i = 0; i < p.options.grid.altitudes_m.size(); ++i) {
        const double a = p.options.grid.altitudes_m[i];
        cv::line(img, {kMargin + static_cast<int>(i) * 150, y - 4}, {kMargin + static_cast<int>(i) * 150 + 30, y - 4},
                 altitude_colour(a, max_alt), 3);
        cv::putText(img, log::cat(a, " m above"), {kMargin + static_cast<int>(i) * 150 + 36, y},
                    cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
    }
    cv::putText(img, "green: measured square/volume, grey: reference path", {kMargin + 460, y},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
    plot::write_png(img, png_path);
}

}  // namespace dw::planner
