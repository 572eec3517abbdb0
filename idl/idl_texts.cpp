#include "idl/idl_texts.hpp"

#include <map>
#include <set>
#include <sstream>

namespace dw::idl {
namespace detail {
const std::map<std::string_view, std::string_view>& texts();
}

std::string_view text(std::string_view file) {
    const auto& t = detail::texts();
    auto it = t.find(file);
    return it == t.end() ? std::string_view() : it->second;
}

namespace {
void inline_file(std::string_view file, std::set<std::string>& done, std::string& out) {
    if (!done.insert(std::string(file)).second) return;
    std::istringstream in{std::string(text(file))};
    std::string line, body;
    while (std::getline(in, line)) {
        const auto first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line[first] == '#') {
            const auto q1 = line.find('"'), q2 = line.rfind('"');
            if (line.find("include", first) != std::string::npos && q1 != std::string::npos && q2 > q1) {
                std::string inc = line.substr(q1 + 1, q2 - q1 - 1);
                if (inc.size() > 4 && inc.substr(inc.size() - 4) == ".idl") inc.resize(inc.size() - 4);
                inline_file(inc, done, out);
            }
            continue;
        }
        body += line;
        body += '\n';
    }
    out += body;
}
}  // namespace

std::string resolved(std::string_view file) {
    std::set<std::string> done;
    std::string out;
    inline_file(file, done, out);
    return out;
}

}  // namespace dw::idl
