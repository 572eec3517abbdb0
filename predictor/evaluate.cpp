#include "predictor/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"

namespace dw::predictor {

Wrench6 predict(const ForceModel& model, const Dataset& data, const Sample& s) {
    return model.predict(s, data.sources[static_cast<std::size_t>(s.source)]);
}

AxisValues rmse(const ForceModel& model, const Dataset& data) {
    AxisValues sq{}, n{};
    for (const auto& s : data.samples) {
        const auto p = predict(model, data, s);
        const auto& measured = data.sources[static_cast<std::size_t>(s.source)].measured;
        for (std::size_t a = 0; a < 6; ++a) {
            if (!measured[a]) continue;
            sq[a] += (p[a] - s.y[a]) * (p[a] - s.y[a]);
            n[a] += 1;
        }
    }
    for (std::size_t a = 0; a < 6; ++a) sq[a] = n[a] > 0 ? std::sqrt(sq[a] / n[a]) : NAN;
    return sq;
}

PeakError peak_error(const ForceModel& model, const Dataset& data, int axis) {
    struct Peak {
        double recorded = -INFINITY, predicted = -INFINITY;
    };
    std::map<std::pair<int, int>, Peak> blocks;  // (source, block)
    const auto a = static_cast<std::size_t>(axis);
    for (const auto& s : data.samples) {
        if (s.leg < 0 || s.k == 0) continue;
        auto& b = blocks[{s.source, s.leg}];
        b.recorded = std::max(b.recorded, s.y[a]);
        b.predicted = std::max(b.predicted, predict(model, data, s)[a]);
    }
    double sum = 0;
    for (const auto& [key, b] : blocks) sum += std::abs(b.predicted - b.recorded);
    PeakError e;
    e.blocks = blocks.size();
    e.mean_abs = blocks.empty() ? NAN : sum / static_cast<double>(blocks.size());
    return e;
}

namespace {

// |mean prediction − mean truth| in each occupied cell of the altitude band.
std::vector<AxisValues> cell_errors(const ForceModel& model, const Dataset& data, const ArenaOptions& o) {
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
        auto& cell =
            cells[{static_cast<int>(std::floor(c[0] / o.cell_m)), static_cast<int>(std::floor(c[1] / o.cell_m))}];
        const auto p = predict(model, data, s);
        for (std::size_t a = 0; a < 6; ++a) {
            cell.pred[a] += p[a];
            cell.truth[a] += s.y[a];
        }
        ++cell.n;
    }
    std::vector<AxisValues> out;
    for (const auto& [key, cell] : cells) {
        AxisValues e{};
        for (std::size_t a = 0; a < 6; ++a) e[a] = std::abs(cell.pred[a] - cell.truth[a]) / cell.n;
        out.push_back(e);
    }
    return out;
}

// Σ over the cells × `weight`; NaN on every axis when no cell is occupied.
AxisValues cell_sum(const std::vector<AxisValues>& cells, double weight) {
    AxisValues out{};
    if (cells.empty()) {
        out.fill(NAN);
        return out;
    }
    for (const auto& e : cells)
        for (std::size_t a = 0; a < 6; ++a) out[a] += e[a] * weight;
    return out;
}

}  // namespace

AxisValues arena_error(const ForceModel& model, const Dataset& data, const ArenaOptions& o) {
    const auto cells = cell_errors(model, data, o);  // Σ|Δ|·A_cell / (cells·A_cell)
    return cell_sum(cells, cells.empty() ? 0.0 : 1.0 / static_cast<double>(cells.size()));
}

AxisValues arena_integral(const ForceModel& model, const Dataset& data, const ArenaOptions& o) {
    return cell_sum(cell_errors(model, data, o), o.cell_m * o.cell_m);
}

std::vector<ComparisonRow> compare(const std::vector<const ForceModel*>& models, const Dataset& test,
                                   const ArenaOptions& o, const NoiseModel* noise) {
    std::set<std::string> formations;
    for (const auto& s : test.sources) formations.insert(s.formation);
    std::vector<ComparisonRow> rows;
    for (const auto& f : formations) {
        const Dataset d = test.with_formation(f);
        if (d.samples.empty()) continue;
        for (const auto* m : models) {
            const auto peak = peak_error(*m, d);
            rows.push_back({f, m->name(), d.samples.size(), arena_error(*m, d, o), arena_integral(*m, d, o),
                            rmse(*m, d), peak.mean_abs, peak.blocks, noise ? coverage(*m, d, *noise) : NAN});
        }
    }
    return rows;
}

namespace {
const char* const kAxisTitles[6] = {"N", "E", "D", "roll", "pitch", "yaw"};

// The formations and the models of `rows`, each in first-seen order.
std::pair<std::vector<std::string>, std::vector<std::string>> formations_and_models(
    const std::vector<ComparisonRow>& rows) {
    std::vector<std::string> order, models;
    for (const auto& r : rows) {
        if (std::find(order.begin(), order.end(), r.formation) == order.end()) order.push_back(r.formation);
        if (std::find(models.begin(), models.end(), r.model) == models.end()) models.push_back(r.model);
    }
    return {order, models};
}

// The row of model m on formation f, or null (a reference over some flights only): its cells "–",
// so that every cell holds one value per model, in the models' order.
const ComparisonRow* row_of(const std::vector<ComparisonRow>& rows, const std::string& f, const std::string& m) {
    const auto it = std::find_if(rows.begin(), rows.end(),
                                 [&](const ComparisonRow& r) { return r.formation == f && r.model == m; });
    return it == rows.end() ? nullptr : &*it;
}

void table(std::ostringstream& out, const std::vector<ComparisonRow>& rows, AxisValues ComparisonRow::*metric) {
    const auto [order, models] = formations_and_models(rows);
    out << "| formation | samples |";
    for (const auto* a : kAxisTitles) out << " " << a << " |";
    out << "\n|---|---|";
    for (int i = 0; i < 6; ++i) out << "---|";
    out << "\n";
    for (const auto& f : order) {
        std::size_t samples = 0;
        std::array<std::string, 6> cellv;
        for (const auto& m : models) {
            const ComparisonRow* r = row_of(rows, f, m);
            if (r && samples == 0) samples = r->samples;  // the first model's: the reference's may be fewer
            for (std::size_t a = 0; a < 6; ++a) {
                if (!cellv[a].empty()) cellv[a] += " / ";
                cellv[a] += fixed(r ? (r->*metric)[a] : NAN, 3);  // "–" where none
            }
        }
        out << "| " << f << " | " << samples << " |";
        for (const auto& c : cellv) out << " " << c << " |";
        out << "\n";
    }
}

// One column per model, one row per formation: `value` of each (– where a model has no row), and
// `count` of the formation's first model.
void per_model(std::ostringstream& out, const std::vector<ComparisonRow>& rows, const char* count_title,
               std::size_t ComparisonRow::*count, double ComparisonRow::*value) {
    const auto [order, models] = formations_and_models(rows);
    out << "| formation | " << count_title << " |";
    for (const auto& m : models) out << " " << m << " |";
    out << "\n|---|---|";
    for (std::size_t m = 0; m < models.size(); ++m) out << "---|";
    out << "\n";
    for (const auto& f : order) {
        std::string cells;
        std::size_t n = 0;
        for (const auto& m : models) {
            const ComparisonRow* r = row_of(rows, f, m);
            cells += " " + fixed(r ? r->*value : NAN, 3) + " |";
            if (r && n == 0) n = r->*count;  // the first model's: the reference's may be fewer
        }
        out << "| " << f << " | " << n << " |" << cells << "\n";
    }
}
}  // namespace

std::string to_markdown(const std::vector<ComparisonRow>& rows, const ArenaOptions& o) {
    const auto [order, models] = formations_and_models(rows);
    std::ostringstream out;
    out << "Held-out blocks (legs, or encounters in flights without legs). Each cell: " << log::join(models, " / ")
        << ".\n\n";
    const bool any_arena = std::any_of(rows.begin(), rows.end(), [](const ComparisonRow& r) {
        return std::any_of(r.arena.begin(), r.arena.end(), [](double v) { return std::isfinite(v); });
    });
    if (any_arena) {
        out << "### Arena-mean |prediction − truth| at " << fixed(o.altitude_m, 2) << " ± " << fixed(o.band_m, 2)
            << " m relative altitude (the study's Table 1 metric; N, N·m)\n\n";
        table(out, rows, &ComparisonRow::arena);
        out << "\n### The same |prediction − truth| integrated over the occupied cells (N·m², N·m³)\n\n"
               "A formation that occupies more of the arena weighs more here; the mean above does not depend on the "
               "coverage.\n\n";
        table(out, rows, &ComparisonRow::arena_integral);
        out << "\n";
    }
    out << "### RMSE over all held-out samples (N, N·m; – where no flight measures the axis)\n\n";
    table(out, rows, &ComparisonRow::rmse);
    out << "\n### Peak f_d error per held-out block: mean |max predicted − max recorded| (N)\n\n";
    per_model(out, rows, "blocks", &ComparisonRow::blocks, &ComparisonRow::peak_error);
    const bool any_coverage =
        std::any_of(rows.begin(), rows.end(), [](const ComparisonRow& r) { return std::isfinite(r.coverage_f_d); });
    if (any_coverage) {
        out << "\n### 95 % prediction intervals: the share of held-out f_d samples inside (0.95 if the model and its "
               "noise model hold; σ² = floor² + (s p)² + (τ dp/dt)², physics/prediction_noise.hpp)\n\n";
        per_model(out, rows, "samples", &ComparisonRow::samples, &ComparisonRow::coverage_f_d);
    }
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
        for (const auto& [name, metric] :
             {std::pair{"arena_mean_abs", &ComparisonRow::arena},
              std::pair{"arena_integral", &ComparisonRow::arena_integral}, std::pair{"rmse", &ComparisonRow::rmse}}) {
            CsvRow row;
            row.text(r.formation).text(r.model).text(name).count(static_cast<long long>(r.samples));
            for (std::size_t a = 0; a < 6; ++a) row.num((r.*metric)[a]);  // empty: no sample in the band
            out << row.line();
        }
    // The peak error and the intervals' coverage are of f_d only (the third axis).
    const auto f_d_only = [&](const ComparisonRow& r, const char* metric, std::size_t n, double v) {
        out << CsvRow()
                   .text(r.formation)
                   .text(r.model)
                   .text(metric)
                   .count(static_cast<long long>(n))
                   .empty(2)
                   .num(v)
                   .empty(3)
                   .line();
    };
    for (const auto& r : rows) {
        f_d_only(r, "peak_f_d_mean_abs", r.blocks, r.peak_error);
        if (std::isfinite(r.coverage_f_d)) f_d_only(r, "interval95_coverage", r.samples, r.coverage_f_d);
    }
    return out.str();
}

void require_samples(const Dataset& all, const Dataset& part, const std::string& what) {
    auto with_neighbour = [](const Sample& s) { return s.k > 0; };
    if (std::any_of(part.samples.begin(), part.samples.end(), with_neighbour)) return;
    std::size_t in_blocks = 0, near = 0;
    for (const auto& s : all.samples) in_blocks += s.leg >= 0 ? 1 : 0, near += s.k > 0 ? 1 : 0;
    throw InputError(log::cat("--data: no ", what, " samples with a neighbour: ", all.sources.size(),
                              " flight(s) gave ", all.samples.size(), " samples, ", in_blocks,
                              " of them in cross-validation blocks, ", near,
                              " with a neighbour; the split holds out blocks with block % ", kSplitPeriod,
                              " == 0, so a flight needs a neighbour within 3 m of the sufferer and at least ",
                              kSplitPeriod, " blocks (legs, encounters or stretches of time)"));
}

namespace {
// The held-out flights' reference models, in first-seen order; the flights without one in `missing`.
std::vector<std::string> references_of(const Dataset& test, std::vector<std::string>& missing, std::size_t& flights) {
    std::vector<bool> used(test.sources.size(), false);
    for (const auto& s : test.samples) used[static_cast<std::size_t>(s.source)] = true;
    std::vector<std::string> words;
    flights = 0;
    for (std::size_t i = 0; i < test.sources.size(); ++i) {
        if (!used[i]) continue;
        ++flights;
        const auto& r = test.sources[i].reference;
        if (r.empty()) missing.push_back(test.sources[i].name);
        else if (std::find(words.begin(), words.end(), r) == words.end()) words.push_back(r);
    }
    return words;
}
}  // namespace

Compared compare_with_reference(const std::vector<const ForceModel*>& models, const Dataset& test,
                                const ArenaOptions& o, const NoiseModel* noise) {
    static const ReferenceModel reference;
    std::vector<std::string> missing;
    std::size_t flights = 0;
    const auto words = references_of(test, missing, flights);
    Compared c{compare(models, test, o, noise), "", !words.empty() && missing.empty(), ""};
    if (noise && !noise->from_class.empty())
        c.noise_note +=
            log::cat("The 95 % intervals' floor of ", log::join(noise->from_class),
                     " (too few samples where no jet reaches) is their sufferer class's, from its other flights.\n\n");
    if (noise && !noise->from_differences.empty())
        c.noise_note += log::cat("The 95 % intervals' floor of ", log::join(noise->from_differences),
                                 " is their jitter (successive differences: no jet-free samples there, nor in any "
                                 "flight of their class), which leaves out the slow error: too narrow.\n\n");
    if (words.empty()) {
        if (!missing.empty()) c.reference_note = "No reference row: no held-out flight carries reference.csv.\n\n";
        return c;
    }
    auto rows = compare({&reference}, c.reference_everywhere ? test : test.with_reference(), o, noise);
    const std::size_t with = flights - missing.size();
    const std::string name = c.reference_everywhere
                                 ? reference.name()
                                 : log::cat(reference.name(), " (", with, " of ", flights, " flights)");
    for (auto& r : rows) r.model = name;
    c.rows.insert(c.rows.end(), rows.begin(), rows.end());
    c.reference_note = log::cat(
        "The row \"", name, "\" is the prediction recorded with the flights (reference.csv): ", log::join(words, "; "),
        c.reference_everywhere
            ? ", on the same held-out samples.\n\n"
            : log::cat(", over the held-out samples of the ", with, " flight(s) that carry one; not over ",
                       log::join(missing), " (the other rows are over all ", flights, ").\n\n"));
    return c;
}

std::string poses_note(const Dataset& d) {
    std::vector<std::string> estimated;
    for (const auto& s : d.sources)
        if (s.estimated_poses) estimated.push_back(s.name);
    if (estimated.empty()) return "";
    return log::cat("The poses of ", estimated.size(),
                    " flight(s) are the vehicles' own state estimates, not motion "
                    "capture (",
                    log::join(estimated),
                    "): the relative positions the models see carry the "
                    "estimators' errors.\n\n");
}

}  // namespace dw::predictor
