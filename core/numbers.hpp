#pragma once
// Numbers at the edges: the one validation rule for every numeric option and configuration value
// (finite and inside a stated range, the range named in the error), and number formatting that
// cannot write past what it formatted.
#include <chrono>
#include <string>
#include <string_view>
#include <vector>

namespace dw {

// A closed interval an input must lie in. contains() is a positive check: NaN and ±inf are never
// inside, whatever the bounds.
struct Range {
    double lo = 0;
    double hi = 0;
    std::string_view unit = "";

    bool contains(double v) const;
    std::string describe() const;  // "[0.05, 5] m/s"
};

// Ranges several tools share.
inline constexpr Range kSeedRange{0, 9007199254740992.0};  // 2^53: every seed a double can say exactly
inline constexpr Range kPortRange{0, 65535};               // a TCP port; 0 = any free one where a tool says so
inline constexpr Range kTimeoutRange{0, 86400, "s"};       // 0 = no limit where a tool says so

// Why `v` is not acceptable for `r` ("nan is not a finite number", "7 is not in [0, 1.4] m"),
// or "" when it is.
std::string range_problem(double v, const Range& r);
// Returns v, or throws dw::InputError "<what>: <problem>".
double require_in(double v, const Range& r, std::string_view what);

// A whole decimal number ("1.5", "-2e-3"); throws dw::InputError "<what>: '<text>' is not a number".
double parse_number(std::string_view text, std::string_view what);
// Comma-separated numbers, each inside r; at least one.
std::vector<double> parse_number_list(std::string_view text, const Range& r, std::string_view what);

// A checked duration in whole milliseconds, rounded up: a positive time never becomes 0 (which
// several options read as "no limit").
std::chrono::milliseconds to_millis(double seconds);

// Appends v with `decimals` digits after the point. Throws dw::InputError naming `what` when v is
// not finite: no NaN or inf reaches a file.
void append_fixed(std::string& out, double v, int decimals, std::string_view what);
// append_fixed without the error: false (and nothing appended) for a value it would refuse. For hot
// loops whose error context costs more than the number (build it only when this fails).
bool try_append_fixed(std::string& out, double v, int decimals);
// A CSV cell: v with `significant` digits (%g), or empty for NaN and inf (a cell with no value):
// no CSV a tool writes holds "nan" or "inf".
std::string csv_cell(double v, int significant = 6);
// One row of a CSV table, its cells in order — numbers as csv_cell writes them, text and counts as
// they are — ended by line(). The one way the tools write a CSV row.
class CsvRow {
public:
    CsvRow& num(double v, int significant = 6) { return cell(csv_cell(v, significant)); }
    CsvRow& text(std::string_view v) { return cell(v); }
    CsvRow& count(long long v) { return cell(std::to_string(v)); }
    CsvRow& empty(int n = 1) {
        for (int i = 0; i < n; ++i) cell("");
        return *this;
    }
    std::string line() const { return row_ + "\n"; }

private:
    CsvRow& cell(std::string_view v) {
        if (!first_) row_ += ',';
        row_ += v;
        first_ = false;
        return *this;
    }
    std::string row_;
    bool first_ = true;
};
// v with `decimals` digits after the point, for reports and tables; "–" (no value) for NaN and inf.
std::string fixed(double v, int decimals);

}  // namespace dw
