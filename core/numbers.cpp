#include "core/numbers.hpp"

#include <cstdio>
#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw {

bool Range::contains(double v) const { return std::isfinite(v) && v >= lo && v <= hi; }

namespace {
// The shortest text that reads back as exactly v (no 6-digit rounding in messages).
std::string exact(double v) {
    char buf[32];
    const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), v);
    return ec == std::errc() ? std::string(buf, ptr) : log::cat(v);
}
}  // namespace

std::string Range::describe() const {
    std::string s = "[" + exact(lo) + ", " + exact(hi) + "]";
    if (!unit.empty()) s += log::cat(" ", unit);
    return s;
}

std::string range_problem(double v, const Range& r) {
    if (!std::isfinite(v)) return exact(v) + " is not a finite number (expected " + r.describe() + ")";
    if (!r.contains(v)) return exact(v) + " is not in " + r.describe();
    return "";
}

double require_in(double v, const Range& r, std::string_view what) {
    const std::string problem = range_problem(v, r);
    if (!problem.empty()) throw InputError(log::cat(what, ": ", problem));
    return v;
}

double parse_number(std::string_view text, std::string_view what) {
    const std::string_view original = text;
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
    if (text.size() > 1 && text.front() == '+') text.remove_prefix(1);
    double v = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, v);
    // from_chars leaves out-of-range magnitudes as an error: they are not usable numbers either.
    if (text.empty() || ec != std::errc() || ptr != end) {
        throw InputError(log::cat(what, ": '", original, "' is not a number"));
    }
    return v;
}

std::vector<double> parse_number_list(std::string_view text, const Range& r, std::string_view what) {
    std::vector<double> out;
    std::size_t start = 0;
    for (;;) {
        const std::size_t comma = text.find(',', start);
        const std::string_view item = text.substr(start, comma == std::string_view::npos ? comma : comma - start);
        out.push_back(require_in(parse_number(item, what), r, what));
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    return out;
}

std::chrono::milliseconds to_millis(double seconds) {
    return std::chrono::milliseconds(static_cast<long long>(std::ceil(seconds * 1000.0)));
}

bool try_append_fixed(std::string& out, double v, int decimals) {
    if (!std::isfinite(v)) return false;
    // A double in fixed notation has at most 309 integer digits; decimals are bounded by the caller.
    char buf[400];
    const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed, decimals);
    if (ec != std::errc()) return false;
    out.append(buf, static_cast<std::size_t>(ptr - buf));
    return true;
}

void append_fixed(std::string& out, double v, int decimals, std::string_view what) {
    if (try_append_fixed(out, v, decimals)) return;
    if (!std::isfinite(v)) throw InputError(log::cat(what, ": ", v, " is not a finite number"));
    throw InputError(log::cat(what, ": ", v, " does not fit a number field"));
}

std::string fixed(double v, int decimals) {
    if (!std::isfinite(v)) return "–";  // no value: a report never says nan or inf
    std::string s;
    append_fixed(s, v, decimals, "fixed");
    return s;
}

std::string csv_cell(double v, int significant) {
    if (!std::isfinite(v)) return "";
    char text[40];
    std::snprintf(text, sizeof text, "%.*g", significant, v);
    return text;
}

}  // namespace dw
