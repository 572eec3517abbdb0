#pragma once
// The viewer's own page (viewer/page/, compiled into the binary by viewer/CMakeLists.txt): HTML and
// JavaScript with no build step and nothing fetched from elsewhere.
#include <string_view>

namespace dw::viewer {

struct PageFile {
    std::string_view path;  // "/", "/app.js"
    std::string_view content_type;
    std::string_view body;
};
// The file served at `target` (its query string ignored), or nullptr.
const PageFile* page_file(std::string_view target);

}  // namespace dw::viewer
