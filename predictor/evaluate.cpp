#include "predictor/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

namespace dw::predictor {

AxisValues rmse(const ForceModel& model, const Dataset& data) {
    AxisValues sq{};
    for (const auto& s : data.samples) {
        const auto p = model.predict(s.neighbours());
        for (std::size_t a = 0; a < 6; ++a) sq[a] += (p[a] - s.y[a]) * (p[a] - s.y[a]);
    }
    for (auto& v : sq) v = data.samples.empty() ? NAN : std::sqrt(v / static_cast<double>(data.samples.size()));
    return sq;
}

AxisValues arena_error(const ForceModel& model, const Dataset& data, const ArenaOptions& o) {
    struct Cell {
        AxisValues pred{}, truth{};
        int n = 0;
    };
    std::map<std::pair<int, int>, Cell> cells;
    for (const auto& s : data.samples) {
        if (s.k == 0) continue;
        const auto c = s.reference();
        if (std::abs(c[2] - o.altitude_m) > o.band_m) continue;
        if (std::abs(c[0]) > o.half_width_m || std::abs(c[1]) > o.half_width_m) continue;
        auto& cell = cells[{static_cast<int>(std::floor(c[0] / o.cell_m)), static_cast<int>(std::floor(c[1] / o.cell_m))}];
        const auto p = model.predict(s.neighbours());
        for (std::size_t a = 0; a < 6; ++a) {
            cell.pred[a] += p[a];
            cell.truth[a] += s.y[a];
        }
        ++cell.n;
    }
    AxisValues out{};
    if (cells.empty()) {
        out.fill(NAN);
        return out;
    }
    for (const auto& [key, cell] : cells)
        for (std::size_t a = 0; a < 6; ++a) out[a] += std::abs(cell.pred[a] - cell.truth[a]) / cell.n;
    for (auto& v : out) v /= static_cast<double>(cells.size());  // Σ|Δ|·A_cell / (cells·A_cell)
    return out;
}

std::vector<ComparisonRow> compare(const std::vector<const ForceModel*>& models, const Dataset& test,
                                   const ArenaOptions& o) {
    std::set<std::string> formations;
    for (const auto& s : test.sources) formations.insert(s.formation);
    std::vector<ComparisonRow> rows;
    for (const auto& f : formations) {
        const Dataset d = test.with_formation(f);
        if (d.samples.empty()) continue;
        for (const auto* m : models) rows.push_back({f, m->name(), d.samples.size(), arena_error(*m, d, o), rmse(*m, d)});
    }
    return rows;
}

namespace {
const char* const kAxisTitles[6] = {"N", "E", "D", "roll", "pitch", "yaw"};

std::string fmt(double v, int precision = 3) {
    if (std::isnan(v)) return "–";
    std::ostringstream s;
    s << std::fixed << std::setprecision(precision) << v;
    return s.str();
}

void table(std::ostringstream& out, const std::vector<ComparisonRow>& rows, bool arena) {
    std::vector<std::string> order;  // formations in first-seen order, models in order
    std::vector<std::string> models;
    for (const auto& r : rows) {
        if (std::find(order.begin(), order.end(), r.formation) == order.end()) order.push_back(r.formation);
        if (std::find(models.begin(), models.end(), r.model) == models.end()) models.push_back(r.model);
    }
    out << "| formation | samples |";
    for (const auto* a : kAxisTitles) out << " " << a << " |";
    out << "\n|---|---|";
    for (int i = 0; i < 6; ++i) out << "---|";
    out << "\n";
    for (const auto& f : order) {
        std::size_t samples = 0;
        std::array<std::string, 6> cellv;
        for (const auto& m : models)
            for (const auto& r : rows)
                if (r.formation == f && r.model == m) {
                    samples = r.samples;
                    for (std::size_t a = 0; a < 6; ++a) {
                        if (!cellv[a].empty()) cellv[a] += " / ";
                        cellv[a] += fmt(arena ? r.arena[a] : r.rmse[a]);
                    }
                }
        out << "| " << f << " | " << samples << " |";
        for (const auto& c : cellv) out << " " << c << " |";
        out << "\n";
    }
}
}  // namespace

std::string to_markdown(const std::vector<ComparisonRow>& rows, const ArenaOptions& o) {
    std::vector<std::string> models;
    for (const auto& r : rows)
        if (std::find(models.begin(), models.end(), r.model) == models.end()) models.push_back(r.model);
    std::string names;
    for (const auto& m : models) names += (names.empty() ? "" : " / ") + m;
    std::ostringstream out;
    out << "Held-out legs. Each cell: " << names << ".\n\n";
    out << "### Arena-mean |prediction − truth| at " << fmt(o.altitude_m, 2) << " ± " << fmt(o.band_m, 2)
        << " m relative altitude (the study's Table 1 metric; N, N·m)\n\n";
    table(out, rows, true);
    out << "\n### RMSE over all held-out samples (N, N·m)\n\n";
    table(out, rows, false);
    return out.str();
}

std::string to_csv(const std::vector<ComparisonRow>& rows, bool header) {
    std::ostringstream out;
    if (header) {
        out << "formation,model,metric,samples";
        for (const auto* a : flight::kAxes) out << "," << a;
        out << "\n";
    }
    for (const auto& r : rows)
        for (int arena = 1; arena >= 0; --arena) {
            out << r.formation << "," << r.model << "," << (arena ? "arena_mean_abs" : "rmse") << "," << r.samples;
            for (std::size_t a = 0; a < 6; ++a) {
                const double v = arena ? r.arena[a] : r.rmse[a];
                out << "," << (std::isnan(v) ? "" : fmt(v, 5));  // empty: no sample in the band
            }
            out << "\n";
        }
    return out.str();
}

}  // namespace dw::predictor
