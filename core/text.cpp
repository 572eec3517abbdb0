#include "core/text.hpp"

#include <cstdint>
#include <cstdio>
#include <cstring>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw {

std::string quote_bytes(std::string_view text, std::size_t n) {
    std::string out;
    std::size_t i = 0;
    for (; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        char piece[5] = {static_cast<char>(c), 0};
        if (c < 0x20 || c >= 0x7f || c == '\\' || c == '\'') std::snprintf(piece, sizeof piece, "\\x%02X", c);
        if (out.size() + std::strlen(piece) > n) break;
        out += piece;
    }
    if (i < text.size()) out += "...";
    return out;
}

bool valid_utf8(std::string_view text) {
    std::size_t i = 0;
    while (i < text.size()) {
        const auto c = static_cast<unsigned char>(text[i]);
        const std::size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
        if (n == 0 || i + n > text.size()) return false;
        std::uint32_t cp = n == 1 ? c : c & (0x7Fu >> n);
        for (std::size_t k = 1; k < n; ++k) {
            const auto d = static_cast<unsigned char>(text[i + k]);
            if ((d >> 6) != 0x2) return false;
            cp = (cp << 6) | (d & 0x3Fu);
        }
        static constexpr std::uint32_t kLeast[] = {0, 0, 0x80, 0x800, 0x10000};  // shortest form per length
        if (cp < kLeast[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
        i += n;
    }
    return true;
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
