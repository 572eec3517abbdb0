#include "flight/reference.hpp"

#include <algorithm>
#include <cmath>

#include "core/files.hpp"
#include "flight/csv.hpp"

namespace dw::flight {

namespace {

std::array<bool, 6> predicted_axes(const ReferenceInfo& info) {
    std::array<bool, 6> on{};
    for (std::size_t a = 0; a < kAxes.size(); ++a)
        on[a] = std::find(info.axes.begin(), info.axes.end(), kAxes[a]) != info.axes.end();
    return on;
}

}  // namespace

std::vector<WrenchSample> read_reference_csv(const std::string& path, const ReferenceInfo& info) {
    csv::CsvReader csv(read_file(path, "flight file"), path);
    csv.expect_header(wrench_columns());
    const auto on = predicted_axes(info);
    std::vector<WrenchSample> out;
    std::vector<std::string_view> row;
    while (csv.next(row)) {
        WrenchSample s;
        s.t = csv.number(row[0], 0, kStampRange);
        for (std::size_t a = 0; a < 6; ++a) {
            if (on[a]) {
                s.w[a] = csv.number(row[a + 1], a + 1, axis_range(a));
            } else if (!row[a + 1].empty()) {
                csv.fail(csv.line(), log::cat("column ", kAxes[a], ": ", csv.quoted(row[a + 1]),
                                              " where the reference predicts nothing (meta.json's reference.axes: ",
                                              log::join(info.axes), "): the cell must be empty"));
            } else {
                s.w[a] = NAN;
            }
        }
        if (!out.empty() && s.t < out.back().t)
            csv.fail(csv.line(),
                     log::cat("t = ", row[0], " is earlier than the row before (rows must be sorted by t)"));
        out.push_back(s);
    }
    if (out.empty()) csv.fail(1, "no samples");
    return out;
}

std::string reference_csv(const std::vector<WrenchSample>& samples, const ReferenceInfo& info) {
    const auto on = predicted_axes(info);
    std::string text = log::join(wrench_columns(), ",") + "\n";
    for (std::size_t i = 0; i < samples.size(); ++i) {
        csv::Row row(text, "reference.csv", i + 2);
        row.number(samples[i].t, 6, "t", kStampRange);
        for (std::size_t a = 0; a < 6; ++a) {
            if (on[a]) row.number(samples[i].w[a], 6, kAxes[a], axis_range(a));
            else row.text("");
        }
    }
    return text;
}

}  // namespace dw::flight
