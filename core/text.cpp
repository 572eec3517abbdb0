#include "core/text.hpp"

#include <cstdio>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw {

std::string quote_bytes(std::string_view text, std::size_t n) {
    std::string out;
    for (std::size_t i = 0; i < text.size() && i < n; ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7f && c != '\\' && c != '\'') {
            out += static_cast<char>(c);
        } else {
            char hex[5];
            std::snprintf(hex, sizeof hex, "\\x%02X", c);
            out += hex;
        }
    }
    if (text.size() > n) out += "...";
    return out;
}

void require_nesting_at_most(std::string_view text, int limit, std::string_view what) {
    int depth = 0;
    bool in_string = false, escaped = false;
    for (char c : text) {
        if (in_string) {
            if (escaped) escaped = false;
            else if (c == '\\') escaped = true;
            else if (c == '"') in_string = false;
            continue;
        }
        if (c == '"') in_string = true;
        else if (c == '[' || c == '{') {
            if (++depth > limit) throw InputError(log::cat(what, ": nests deeper than ", limit, " levels"));
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
}

}  // namespace dw
