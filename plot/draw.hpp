#pragma once
// Small OpenCV drawing helpers shared by the plots (for .cpp files that link OpenCV).
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/numbers.hpp"

namespace dw::plot {

// Dark text at `at`; align 0 left, 1 centred, 2 right.
inline void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, int align = 0,
                 int thickness = 1) {
    int base = 0;
    const auto size = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &base);
    if (align == 1) at.x -= size.width / 2;  // centred
    if (align == 2) at.x -= size.width;      // right-aligned
    cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(20, 20, 20), thickness, cv::LINE_AA);
}

inline cv::Scalar bgr(const std::array<unsigned char, 3>& c) { return {double(c[0]), double(c[1]), double(c[2])}; }

// A 1-2-5 tick step giving about five ticks over range.
inline double nice_step(double range) {
    const double raw = range / 5;
    const double p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * p >= raw) return m * p;
    return 10 * p;
}

}  // namespace dw::plot
