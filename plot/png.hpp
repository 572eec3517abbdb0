#pragma once
// The one way a picture reaches a file: the name must end in .png (checked before any work, with
// require_png_path), the image is encoded in memory and written atomically, and OpenCV's own
// errors become one clear line.
#include <string>
#include <string_view>

namespace cv {
class Mat;
}

namespace dw::plot {

// Throws dw::InputError unless `path` ends in .png and its folder can take a file.
void require_png_path(const std::string& path, std::string_view what);
// Throws dw::RuntimeError naming the path when encoding or writing fails.
void write_png(const cv::Mat& image, const std::string& path);

}  // namespace dw::plot
