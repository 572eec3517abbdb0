#pragma once
// The flight folder's CSV files, read with located errors ("file:line: column x: ...") and written
// row by row with located errors for values that cannot be written. Internal to dw_flight.
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/text.hpp"

namespace dw::flight::csv {

// Splits CSV text into lines of fields; the first line is the header.
class CsvReader {
public:
    CsvReader(std::string text, std::string file) : text_(std::move(text)), file_(std::move(file)) {}

    void expect_header(const std::vector<std::string>& columns) {
        std::vector<std::string_view> fields;
        if (!next(fields)) fail(1, "the file is empty (expected the header line)");
        std::string want, got;
        for (const auto& c : columns) want += (want.empty() ? "" : ",") + c;
        for (auto f : fields) got += (got.empty() ? "" : ",") + std::string(f);
        if (want != got) fail(line_, log::cat("header is ", quoted(got), ", expected '", want, "'"));
        columns_ = columns;
    }
    // Next data row; false at the end. Blank trailing lines are allowed.
    bool next(std::vector<std::string_view>& fields) {
        while (pos_ < text_.size()) {
            std::size_t end = text_.find('\n', pos_);
            if (end == std::string::npos) end = text_.size();
            std::string_view row(text_.data() + pos_, end - pos_);
            pos_ = end + 1;
            ++line_;
            if (!row.empty() && row.back() == '\r') row.remove_suffix(1);
            if (row.empty()) continue;
            fields.clear();
            std::size_t start = 0;
            for (;;) {
                const std::size_t comma = row.find(',', start);
                fields.push_back(
                    row.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
                if (comma == std::string_view::npos) break;
                start = comma + 1;
            }
            if (!columns_.empty() && fields.size() != columns_.size()) {
                fail(line_, log::cat(fields.size(), " fields, expected ", columns_.size(), " (",
                                     log::join(columns_, ","), ")"));
            }
            return true;
        }
        return false;
    }
    // The number in `field`, inside the range the quantity has (flight.hpp): every number a flight
    // file holds goes through one.
    double number(std::string_view field, std::size_t column, const Range& range) const {
        double v = 0;
        const auto* end = field.data() + field.size();
        auto [ptr, ec] = std::from_chars(field.data(), end, v);
        if (ec != std::errc() || ptr != end || field.empty()) {
            fail(line_, log::cat("column ", columns_[column], ": ", quoted(field), " is not a number"));
        }
        if (!range.contains(v)) fail(line_, log::cat("column ", columns_[column], ": ", range_problem(v, range)));
        return v;
    }
    // Input quoted into an error: 'text', escaped and cut short (core/text.hpp).
    static std::string quoted(std::string_view field) { return "'" + quote_bytes(field, kQuotedBytes) + "'"; }
    [[noreturn]] void fail(std::size_t line, const std::string& what) const {
        throw InputError(log::cat(file_, ":", line, ": ", what));
    }
    std::size_t line() const { return line_; }

private:
    std::string text_;
    std::string file_;
    std::size_t pos_ = 0;
    std::size_t line_ = 0;
    std::vector<std::string> columns_;
};

// One CSV row appended to `out` (its newline when it goes out of scope).
class Row {
public:
    Row(std::string& out, const char* file, std::size_t row) : out_(out), file_(file), row_(row) {}
    // v, inside the range its quantity is read with (a tool writes nothing it would refuse to read).
    void number(double v, int decimals, const char* column, const Range& range) {
        if (!range.contains(v))
            throw InputError(
                log::cat("flight to write: ", file_, " row ", row_, " column ", column, ": ", range_problem(v, range)));
        if (!first_) out_ += ',';
        first_ = false;
        if (!try_append_fixed(out_, v, decimals))  // the context is built only for the error
            append_fixed(out_, v, decimals, log::cat("flight to write: ", file_, " row ", row_, " column ", column));
    }
    void text(const std::string& v) {
        if (!first_) out_ += ',';
        first_ = false;
        out_ += v;
    }
    ~Row() { out_ += '\n'; }

private:
    std::string& out_;
    const char* file_;
    std::size_t row_;
    bool first_ = true;
};

}  // namespace dw::flight::csv
