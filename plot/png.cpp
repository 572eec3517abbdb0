#include "plot/png.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <filesystem>
#include <vector>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"

namespace dw::plot {

void require_png_path(const std::string& path, std::string_view what) {
    if (std::filesystem::path(path).extension() != ".png") {
        throw InputError(log::cat(what, " ", path, ": a picture is written as PNG; the name must end in .png"));
    }
    require_writable_path(path, what);
}

void write_png(const cv::Mat& image, const std::string& path) {
    std::vector<unsigned char> bytes;
    try {
        if (!cv::imencode(".png", image, bytes)) throw RuntimeError(log::cat("cannot encode the picture ", path));
    } catch (const cv::Exception& e) {
        throw RuntimeError(log::cat("cannot encode the picture ", path, ": ", e.msg));
    }
    write_file(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace dw::plot
