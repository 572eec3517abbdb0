#include "core/text.hpp"

#include <algorithm>
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

namespace {
std::size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = up;
        }
    }
    return row[b.size()];
}
}  // namespace

namespace {
std::string joined(const std::vector<std::string>& names, std::string_view last) {
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i)
        out += (i == 0 ? "" : i + 1 == names.size() ? std::string(last) : ", ") + names[i];
    return out;
}
}  // namespace

std::string choices(std::string_view given, const std::vector<std::string>& names, std::string_view last) {
    const std::string all = joined(names, last);
    if (all.size() <= kChoicesChars) return all;
    std::vector<std::string> closest = names;
    const std::string_view g = given.substr(0, 64);  // a hostile name need not cost more
    std::stable_sort(closest.begin(), closest.end(), [&](const std::string& a, const std::string& b) {
        return edit_distance(g, a) < edit_distance(g, b);
    });
    const std::string suffix = log::cat("; the closest of ", names.size());
    std::size_t n = 1;  // as many of the closest as fit
    while (n < closest.size() && n < 3 &&
           joined({closest.begin(), closest.begin() + static_cast<std::ptrdiff_t>(n) + 1}, last).size() +
                   suffix.size() <=
               kChoicesChars)
        ++n;
    closest.resize(n);
    return joined(closest, last) + suffix;
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
