#include "predictor/real.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "flight/flight.hpp"
#include "physics/config.hpp"
#include "plot/chart.hpp"
#include "predictor/study.hpp"

namespace dw::predictor {

namespace {

namespace fs = std::filesystem;

constexpr double kMapCell_m = 0.05;
// The physics-informed models' files: models/<kind>_on_physics.json, corrections to add to the physics.
std::string model_file(const std::string& kind, bool correction) {
    return kind + (correction ? kCorrectionFileSuffix : "") + ".json";
}

// Where the horizontally nearest neighbour is: horizontal offset and height above the sufferer.
std::array<double, 2> nearest(const Sample& s) {
    double best = INFINITY, above = 0;
    for (const auto& x : s.neighbours()) {
        const double h = std::hypot(x[0], x[1]);
        if (h < best) best = h, above = -x[2];
    }
    return {best, above};
}

// f_d on the held-out samples against the nearest neighbour's relative position: recorded, then
// each model, on one colour scale.
void draw_maps(const std::vector<const ForceModel*>& models, const Dataset& test, const std::string& png) {
    double off = kMapCell_m, lo = 0, hi = kMapCell_m;
    for (const auto& s : test.samples) {
        if (s.k == 0) continue;
        const auto [h, a] = nearest(s);
        off = std::max(off, h), lo = std::min(lo, a), hi = std::max(hi, a);
    }
    off = std::ceil(off / kMapCell_m) * kMapCell_m, lo = std::floor(lo / kMapCell_m) * kMapCell_m,
    hi = std::ceil(hi / kMapCell_m) * kMapCell_m;
    const int nx = static_cast<int>(std::lround(off / kMapCell_m)),
              ny = static_cast<int>(std::lround((hi - lo) / kMapCell_m));
    auto field = [&](const std::string& title, const ForceModel* m) {
        std::vector<std::array<double, 3>> xs;
        for (const auto& s : test.samples) {
            if (s.k == 0) continue;
            const auto [h, a] = nearest(s);
            xs.push_back(
                {h, a, m ? m->predict(s, test.sources[static_cast<std::size_t>(s.source)])[kFdAxis] : s.y[kFdAxis]});
        }
        return plot::bin_heat(title, xs, 0, off, lo, hi, nx, ny);
    };
    std::vector<plot::Heat> heats{field("recorded", nullptr)};
    for (const auto* m : models) heats.push_back(field(m->name(), m));
    plot::render_heats(heats, "f_d [N] on held-out blocks by where the nearest neighbour is (mean per 5 cm cell)",
                       "horizontal offset [m]", "height above the sufferer [m]", "f_d [N]", png);
}

// A flight's vehicle mix: the sufferer's mass under its neighbours' (grams, sorted), e.g. "32 under 32+67".
std::string vehicle_mix(const Source& s) {
    auto grams = [](const physics::VehicleParams& v) { return static_cast<int>(std::lround(v.mass_kg * 1000)); };
    std::vector<int> above;
    for (const auto& n : s.neighbours) above.push_back(grams(n));
    std::sort(above.begin(), above.end());
    std::vector<std::string> names;
    for (int g : above) names.push_back(std::to_string(g));
    return log::cat(grams(s.sufferer), " under ", log::join(names, "+"));
}

// The seen flights that validate: of each vehicle mix flown in two or more seen flights, the last
// by name, whole (a model stopped on blocks of the flights it trains on learns those flights; one
// stopped on flights it never saw learns what carries over). Empty when no mix has two.
std::vector<int> validating_sources(const Dataset& seen) {
    std::map<std::string, std::vector<int>> by_mix;
    for (std::size_t i = 0; i < seen.sources.size(); ++i)
        by_mix[vehicle_mix(seen.sources[i])].push_back(static_cast<int>(i));
    std::vector<int> out;
    for (const auto& [mix, flights] : by_mix) {
        if (flights.size() < 2) continue;
        out.push_back(*std::max_element(flights.begin(), flights.end(), [&](int a, int b) {
            return seen.sources[static_cast<std::size_t>(a)].name < seen.sources[static_cast<std::size_t>(b)].name;
        }));
    }
    return out;
}

// Leave-trials-out: every block of the unseen flights held out; of the seen flights, those of
// validating_sources validate whole and the others train — or, when none can be spared, every
// seen flight trains with block % 5 == 1 validating.
Split split_by_trial(const Dataset& seen, const Dataset& unseen, std::vector<std::string>& validating) {
    const auto held = validating_sources(seen);
    for (int i : held) validating.push_back(seen.sources[static_cast<std::size_t>(i)].name);
    const Dataset test = unseen.legs_where([](int) { return true; });
    if (held.empty()) {
        Split by_block = split_by_leg(seen);
        by_block.train.append(by_block.test);
        return {by_block.train, by_block.validation, test};
    }
    auto validates = [&](int source) { return std::find(held.begin(), held.end(), source) != held.end(); };
    Dataset train, validation;
    train.sources = validation.sources = seen.sources;
    for (const auto& s : seen.samples)
        if (s.leg >= 0) (validates(s.source) ? validation : train).samples.push_back(s);
    return {std::move(train), std::move(validation), test};
}

// What the physics leaves: each sample's recorded wrench less the physics' prediction (the
// physics-informed models' target).
Dataset less_physics(const Dataset& d, const ForceModel& physics) {
    Dataset out = d;
    for (auto& s : out.samples) {
        const auto p = predict(physics, d, s);
        for (std::size_t k = 0; k < 6; ++k) s.y[k] -= std::isfinite(p[k]) ? p[k] : 0.0;
    }
    return out;
}

// A correction shrunk towards none, axis by axis, by flights it never trained on: the least-squares
// factor in [0, 1] by which its prediction best matches what the physics leaves on `left` (the
// validation flights less the physics). A correction whose shape carries over keeps about 1; one
// that learnt its training flights' own errors goes to about 0 on that axis. Returns the factors.
Wrench6 shrink_to(LearntModel& m, const Dataset& left) {
    Wrench6 cr{}, cc{}, factor{};
    for (const auto& s : left.samples) {
        const auto& src = left.sources[static_cast<std::size_t>(s.source)];
        const auto c = predict(m, left, s);
        for (std::size_t a = 0; a < 6; ++a)
            if (src.measured[a] && std::isfinite(c[a]) && std::isfinite(s.y[a]))
                cr[a] += c[a] * s.y[a], cc[a] += c[a] * c[a];
    }
    for (std::size_t a = 0; a < 6; ++a) {
        factor[a] = cc[a] > 0 ? std::clamp(cr[a] / cc[a], 0.0, 1.0) : 1.0;
        m.output_scale[a] = static_cast<float>(m.output_scale[a] * factor[a]);
    }
    return factor;
}

std::string describe_split(const Dataset& all, const std::vector<std::string>& unseen,
                           const std::vector<std::string>& validating) {
    std::size_t by[3] = {0, 0, 0};
    for (const auto& s : all.sources) ++by[static_cast<int>(s.blocks)];
    const std::string blocks =
        log::cat("flights split by legs: ", by[0], ", by encounters: ", by[1], ", by time: ", by[2]);
    if (unseen.empty())
        return log::cat("blocks by block % ", kSplitPeriod, " (== 0 held out, == 1 validation, else training); ",
                        blocks);
    const std::string held = log::cat("leave-trials-out: every block of ", unseen.size(),
                                      " unseen flight(s) held out (", log::join(unseen), "); ");
    if (validating.empty())
        return log::cat(held, "the others' blocks train, block % ", kSplitPeriod, " == 1 validating; ", blocks);
    return log::cat(held, "of the others, one whole flight of each vehicle mix flown twice or more validates (",
                    log::join(validating), ") and the rest train; ", blocks);
}

// Every flight of --data read, and split: by blocks, or leave-trials-out when --unseen names some.
struct Loaded {
    Dataset all;
    Split split;
    std::vector<std::string> validating;  // seen flights validating whole (leave-trials-out)
};
Loaded load_and_split(const RealOptions& o) {
    Dataset all, seen, unseen;
    DatasetOptions dopt;
    dopt.physics = o.physics;
    for (const auto& p : o.data) {
        throw_if_stopped(o.stop, "reading the flights");
        const Dataset d = load_dataset(p, dopt);
        all.append(d);
        (std::find(o.unseen.begin(), o.unseen.end(), p) == o.unseen.end() ? seen : unseen).append(d);
    }
    for (const auto& u : o.unseen)
        if (std::find(o.data.begin(), o.data.end(), u) == o.data.end())
            throw InputError(log::cat("--unseen ", u, ": not among --data (list every flight in --data)"));
    std::vector<std::string> validating;
    Split split = o.unseen.empty() ? split_by_leg(all) : split_by_trial(seen, unseen, validating);
    require_samples(all, split.test, "held-out");
    require_samples(all, split.train, "training");
    require_samples(all, split.validation, "validation");
    return {std::move(all), std::move(split), std::move(validating)};
}

// The models compared, in the table's order: the physics, the naive sum (two-vehicle flights
// only), learnt linear and Deep Sets, the same two on what the physics leaves, and the
// recording's own reference prediction where it has one.
struct Models {
    explicit Models(const physics::PhysicsConfig& c) : physics(c) {}
    PhysicsModel physics;
    std::unique_ptr<LearntModel> naive, linear, deep, linear_c, deep_c;
    std::unique_ptr<CorrectedModel> linear_p, deep_p;
    ReferenceModel reference;
    std::vector<const ForceModel*> list;
    std::vector<std::string> shrunk;  // each correction's factors per axis (shrink_to)
    std::string baseline;             // which sum model Deep Sets started from, and why
};

// Deep Sets starts from the sum model with the lower f_d RMSE on the validation flights: learnt
// linear, or the naive sum where single-neighbour training carries over to unseen flights better.
const LearntModel* deep_sets_baseline(Models& m, const Dataset& validation) {
    const double linear = rmse(*m.linear, validation)[kFdAxis];
    const double naive = m.naive ? rmse(*m.naive, validation)[kFdAxis] : linear;
    const LearntModel* base = naive < linear ? m.naive.get() : m.linear.get();
    m.baseline = log::cat("Deep Sets starts from ", base->kind, " (validation f_d RMSE: naive_linear ",
                          m.naive ? fixed(naive, 4) : std::string("–"), ", learnt_linear ", fixed(linear, 4), " N). ");
    return base;
}

void train_models(Models& m, const Split& split, const TrainPlan& plan, const fs::path& dir, bool& naive,
                  const std::function<void(const std::string&)>& say) {
    // A correction to the physics starts at none: it moves off the physics only as far as validation agrees.
    auto train = [&](const std::string& kind, const Dataset& tr, const Dataset& va,
                     const LearntModel* baseline = nullptr, bool correction = false) {
        TrainPlan p = plan;
        p.from_zero = correction;
        return train_and_save(kind, tr, va, p, (dir / model_file(kind, correction)).string(), baseline);
    };
    m.list = {&m.physics};
    const Dataset two_tr = split.train.from_two_vehicle_flights(), two_va = split.validation.from_two_vehicle_flights();
    naive = !two_tr.samples.empty() && !two_va.samples.empty();
    if (naive) {
        m.naive = train("naive_linear", two_tr, two_va);
        m.list.push_back(m.naive.get());
    } else {
        say("no two-vehicle flight among the data: the naive linear model is not trained");
    }
    m.linear = train("learnt_linear", split.train, split.validation);
    m.deep = train("deep_sets", split.train, split.validation, deep_sets_baseline(m, split.validation));
    m.list.push_back(m.linear.get());
    m.list.push_back(m.deep.get());
    // Physics-informed: the same two trained on what the (calibrated) physics leaves, serving physics + correction.
    say("training on what the physics leaves");
    const Dataset left_tr = less_physics(split.train, m.physics), left_va = less_physics(split.validation, m.physics);
    m.linear_c = train("learnt_linear", left_tr, left_va, nullptr, true);
    m.deep_c = train("deep_sets", left_tr, left_va, m.linear_c.get(), true);
    for (auto* c : {m.linear_c.get(), m.deep_c.get()}) {
        const auto f = shrink_to(*c, left_va);
        std::vector<std::string> axes;
        for (std::size_t a = 0; a < f.size(); ++a) axes.push_back(log::cat(flight::kAxes[a], " ", fixed(f[a], 2)));
        m.shrunk.push_back(log::cat("physics+", c->kind, ": ", log::join(axes)));
        mark_correction(*c, m.physics.config());
        c->save((dir / model_file(c->kind, true)).string());  // the file train_and_save wrote, shrunk, marked
    }
    m.linear_p = std::make_unique<CorrectedModel>(m.physics, *m.linear_c);
    m.deep_p = std::make_unique<CorrectedModel>(m.physics, *m.deep_c);
    m.list.push_back(m.linear_p.get());
    m.list.push_back(m.deep_p.get());
}

std::string shrink_note(const std::vector<std::string>& shrunk) {
    return log::cat(
        "The corrections (physics+…) are shrunk towards none, axis by axis, by the least-squares factor "
        "in [0, 1] that fits each to what the physics leaves on the validation samples (1: kept whole, "
        "0: what it learnt does not carry over there): ",
        log::join(shrunk, "; "), ".\n\n");
}

std::string table_markdown(const Dataset& all, const std::string& split, const RealResult& r,
                           const std::string& notes) {
    std::string md = "# Force models on recorded flights\n\n";
    for (const auto& s : all.sources)
        md += log::cat("- ", s.name, " (", s.formation, ", ", s.neighbours.size(), " neighbour(s), blocks by ",
                       flight::to_string(s.blocks), ")\n");
    md += log::cat("\nSplit: ", split, ". Training ", r.train, ", validation ", r.validation, ", held out ", r.test,
                   " samples. The naive linear model is trained on two-vehicle flights only",
                   r.naive ? "" : " (none here: not trained)",
                   "; learnt linear and Deep Sets on all. The physics uses each vehicle's own parameters. "
                   "physics+learnt_linear and physics+deep_sets are the physics plus those models trained on what it "
                   "leaves (recorded − physics; their files models/*_on_physics.json are the corrections alone), "
                   "each starting from no correction.\n\n");
    md += notes;
    md += poses_note(all);
    md += to_markdown(r.table, {});
    md += "\n![f_d by relative position](map_f_d.png)\n";
    return md;
}

}  // namespace

RealResult run_real(const RealOptions& o) {
    auto say = [&](const std::string& line) {
        if (o.progress) o.progress(line);
    };
    StagedFolder staged(o.out_dir);  // models, tables and map appear together, or not at all
    const fs::path out(staged.path()), final_out(o.out_dir);
    const auto [all, split, validating] = load_and_split(o);
    const std::string split_text = describe_split(all, o.unseen, validating);
    RealResult r;
    r.train = split.train.samples.size(), r.validation = split.validation.samples.size(),
    r.test = split.test.samples.size();
    say(log::cat(all.samples.size(), " samples from ", all.sources.size(), " flight(s): ", r.train, " training, ",
                 r.validation, " validation, ", r.test, " held out"));
    fs::create_directories(out / "models");
    const TrainPlan plan{.seed = o.seed,
                         .max_epochs = o.max_epochs,
                         .threads = o.threads,
                         .members = o.members,
                         .split = split_text,
                         .progress = o.progress,
                         .stop = o.stop};
    Models m(o.physics);
    train_models(m, split, plan, out / "models", r.naive, say);
    write_file((out / "models" / "physics.yaml").string(), physics::to_yaml(o.physics));

    say("comparing on the held-out blocks");
    const auto noise = noise_model(all, o.physics);
    const auto compared = compare_with_reference(m.list, split.test, {}, &noise);
    r.table = compared.rows;
    if (compared.reference_everywhere) m.list.push_back(&m.reference);  // drawn only where every flight has it
    draw_maps(m.list, split.test, (out / "map_f_d.png").string());
    r.map_path = (final_out / "map_f_d.png").string();
    write_file((out / "table.md").string(),
               table_markdown(all, split_text, r,
                              compared.reference_note + compared.noise_note + m.baseline + shrink_note(m.shrunk)));
    write_file((out / "table.csv").string(), to_csv(r.table));
    staged.commit();
    r.markdown_path = (final_out / "table.md").string();
    r.csv_path = (final_out / "table.csv").string();
    return r;
}

}  // namespace dw::predictor
