#include "predictor/study.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/shutdown.hpp"
#include "flight/flight.hpp"
#include "physics/effect_types.hpp"
#include "physics/flight_sim.hpp"
#include "predictor/ensemble.hpp"
#include "predictor/maps.hpp"
#include "predictor/train.hpp"

namespace dw::predictor {

namespace fs = std::filesystem;

double table_value(const std::vector<ComparisonRow>& rows, const std::string& formation, const std::string& model,
                   int axis, bool arena) {
    for (const auto& r : rows)
        if (r.formation == formation && r.model == model)
            return arena ? r.arena[static_cast<std::size_t>(axis)] : r.rmse[static_cast<std::size_t>(axis)];
    return NAN;
}

std::unique_ptr<LearntModel> train_and_save(const std::string& kind, const Dataset& tr, const Dataset& va,
                                            const TrainPlan& plan, const std::string& path,
                                            const LearntModel* baseline) {
    auto say = [&](const std::string& line) {
        if (plan.progress) plan.progress(line);
    };
    const int members = members_for(kind, plan.members);
    TrainOptions t;
    t.kind = kind;
    t.seed = plan.seed;
    t.from_zero = plan.from_zero;
    t.max_epochs = plan.max_epochs;
    t.threads = plan.threads;
    t.cores = plan.cores;
    t.turn = plan.turn;
    t.stop = plan.stop;
    t.split = plan.split;
    say(log::cat("training ", kind, " on ", tr.samples.size(), " samples",
                 baseline ? log::cat(" (on ", baseline->kind, ")") : "",
                 members > 1 ? log::cat(", ", members, " trainings at once, averaged") : ""));
    auto r = train_members(tr, va, t, members, baseline, say);
    r.model.save(path);
    return std::make_unique<LearntModel>(std::move(r.model));
}

namespace {

void write_text(const fs::path& p, const std::string& text) { write_file(p.string(), text); }

using Say = std::function<void(const std::string&)>;

// 1. Fly: one flight folder per formation, read back through the contract, as many at once as
// there are cores (each seeded by its place in the list, so the flights are those flown one after
// another). `label` maps each physics formation name to its dataset label.
Dataset fly_flights(const StudyOptions& o, const fs::path& out, std::map<std::string, std::string>& label,
                    const Say& say) {
    std::vector<Dataset> flown(o.formations.size());
    parallel_for(flown.size(), o.jobs, [&](std::size_t i) {
        const std::string& f = o.formations[i];
        physics::FlyOptions fly;
        fly.formation = f;
        fly.grid.legs = o.legs;
        // Single-neighbour flights cover where the formations' vehicles go (up to 0.5 m beyond the
        // formations' centre), so the sum of single-neighbour models is not extrapolating.
        // As many more legs as keep the lines as close together (narrow jets at 0.3 m).
        if (f == "single") {
            fly.grid.half_width_m = o.single_half_width_m;
            fly.grid.legs = static_cast<int>(std::lround(o.legs * o.single_half_width_m / 1.0));
        }
        fly.seed = o.seed + i;
        fly.stop = o.stop;
        const fs::path dir = out / "flights" / f;
        say(log::cat("flying ", f, " (", fly.grid.legs, " legs, simulated)"));
        flight::write_flight(physics::simulate_flight(o.physics, fly).flight, dir.string());
        flown[i] = load_dataset(dir.string());
    });
    Dataset all;
    for (std::size_t i = 0; i < flown.size(); ++i) {
        label[o.formations[i]] = flown[i].sources.front().formation;
        all.append(flown[i]);
    }
    return all;
}

Dataset without(const Dataset& d, const std::string& f1, const std::string& f2) {
    Dataset x;
    x.sources = d.sources;
    for (const auto& s : d.samples) {
        const auto& f = d.sources[static_cast<std::size_t>(s.source)].formation;
        if (f != f1 && f != f2) x.samples.push_back(s);
    }
    return x;
}

using Trainer =
    std::function<std::unique_ptr<LearntModel>(const std::string& kind, const Dataset& tr, const Dataset& va,
                                               const std::string& file, const LearntModel* baseline)>;

// 4. Generalisation: K <= 2 -> K = 3, and a formation left out. The two are independent: the
// second trains on another thread meanwhile (each training single-threaded, seeded as if alone).
std::vector<ComparisonRow> generalisation(const Split& split, const ForceModel& naive, const Trainer& train,
                                          const ArenaOptions& arena) {
    auto test = [&](const Dataset& tr, const Dataset& va, const std::string& tag, const Dataset& held_out,
                    const std::string& label) {
        auto lin = train("learnt_linear", tr, va, "learnt_linear." + tag + ".json", nullptr);
        auto deep = train("deep_sets", tr, va, "deep_sets." + tag + ".json", lin.get());
        auto rows = compare({&naive, lin.get(), deep.get()}, held_out, arena);
        for (auto& row : rows) row.formation += label;
        return rows;
    };
    const auto ns_tr = without(split.train, "stack K=2", ""), ns_va = without(split.validation, "stack K=2", "");
    auto no_stack = std::async(std::launch::async, test, std::cref(ns_tr), std::cref(ns_va), "no_stack",
                               split.test.with_formation("stack K=2"), " (stack left out)");
    auto out = test(without(split.train.with_k(0, 2), "leader_follower K=3", "hybrid K=3"),
                    without(split.validation.with_k(0, 2), "leader_follower K=3", "hybrid K=3"), "k_le_2",
                    split.test.with_k(3, 3), " (trained on K ≤ 2)");
    const auto rest = no_stack.get();
    out.insert(out.end(), rest.begin(), rest.end());
    return out;
}

// 2. The study's own trainings take a core each at once (each single-threaded, seeded as if alone):
// naive linear beside learnt linear, then Deep Sets' members together. The generalisation, which
// compares with naive linear, starts when that is trained and fills the cores they leave free.
struct Trained {
    std::unique_ptr<LearntModel> naive, linear, deep;
    std::future<std::vector<ComparisonRow>> generalised;  // when asked for: still training
};

Trained train_models(const StudyOptions& o, const Split& split, const fs::path& out, Cores& cores) {
    const TrainPlan plan{.seed = o.seed,
                         .max_epochs = o.max_epochs,
                         .threads = o.threads,
                         .members = o.members,
                         .cores = &cores,
                         .split = "by leg: leg % 5 == 1 validation, leg % 5 == 0 held out for testing, else training",
                         .progress = o.progress,
                         .stop = o.stop};
    auto trainer = [&out](const TrainPlan& p) -> Trainer {
        return [&out, p](const std::string& kind, const Dataset& tr, const Dataset& va, const std::string& file,
                         const LearntModel* baseline) {
            return train_and_save(kind, tr, va, p, (out / "models" / file).string(), baseline);
        };
    };
    const Trainer train = trainer(plan);
    // The generalisation tests train one Deep Sets each, not an average (the study's time budget):
    // they ask whether a model carries over to formations it has not seen, not how near the floor it is.
    TrainPlan filler = plan;
    filler.members = 1;
    filler.turn = Cores::Turn::when_free;
    auto singles = [](const Dataset& d) { return d.from_two_vehicle_flights().with_k(1, 1); };
    Trained t;
    auto naive_f = std::async(std::launch::async, [&] {
        auto naive =
            train("naive_linear", singles(split.train), singles(split.validation), "naive_linear.json", nullptr);
        if (o.generalisation)
            t.generalised = std::async(std::launch::async, [&split, &o, n = naive.get(), f = trainer(filler)] {
                return generalisation(split, *n, f, o.arena);
            });
        return naive;
    });
    t.linear = train("learnt_linear", split.train, split.validation, "learnt_linear.json", nullptr);
    t.naive = naive_f.get();
    t.deep = train("deep_sets", split.train, split.validation, "deep_sets.json", t.linear.get());
    return t;
}

ArenaOptions arena_at(const ArenaOptions& arena,
                      double altitude) {  // the study's arena, at one of the flights' altitudes
    ArenaOptions at = arena;
    at.altitude_m = altitude;
    return at;
}

// The maps of every multi-vehicle formation; returns their Markdown.
std::string draw_maps(const StudyOptions& o, const fs::path& out, const std::vector<const ForceModel*>& models,
                      const Dataset& all, const std::map<std::string, std::string>& label) {
    fs::create_directories(out / "maps");
    std::string md = "\n## Maps\n\n";
    for (const auto& f : o.formations) {
        if (f == "single") continue;
        throw_if_stopped(o.stop, "the maps");
        MapRequest req;
        req.formation = f;
        req.altitude_m = o.arena.altitude_m;
        req.observed = all.with_formation(label.at(f));
        const auto png = (out / "maps" / (f + ".png")).string();
        const auto line = (out / "maps" / (f + "_line.png")).string();
        draw_force_map(models, req, png);
        draw_force_line(models, req, line);
        md += log::cat("![", f, "](maps/", f, ".png)\n![", f, " along E](maps/", f, "_line.png)\n\n");
    }
    return md;
}

// The effects of the vocabulary switched on in e ("none").
std::string effects_on(const physics::Effects& e) {
    std::vector<std::string> on;
    for (const auto* t : physics::effect_types())
        if (t->enabled(e)) on.push_back(t->name());
    return on.empty() ? "none" : log::join(on);
}

// 5. table.md (without the maps) and the banded rows for the CSV.
std::string tables_markdown(const StudyOptions& o, const StudyResult& r, std::vector<ComparisonRow>& banded) {
    std::string md = "# Force models compared\n\n";
    md += log::cat("Simulated flights (", o.legs, " legs each, seed ", o.seed, "; aggregation ",
                   o.physics.aggregation == physics::Aggregation::force_sum ? "force sum" : "velocity superposition",
                   "; effects on: ", effects_on(o.physics.effects), ").\n\n");
    md += to_markdown(r.table, o.arena);
    md += "\n## By altitude band (the flights' three altitudes; RMSE over the held-out samples within the band)\n\n";
    for (const auto& [altitude, rows] : r.by_altitude) {
        md += log::cat("### ", altitude, " m\n\n", to_markdown(rows, arena_at(o.arena, altitude)), "\n");
        for (auto row : rows) {
            row.formation += log::cat(" @ ", altitude, " m");
            banded.push_back(row);
        }
    }
    md += "\n## Regimes\n\n" + regimes_markdown(r.regimes, RegimeOptions{}) + "\n![regimes](regimes.png)\n";
    if (!r.generalisation.empty()) {
        md += "\n## Generalisation (held-out legs of formations the models were not trained on)\n\n";
        md += to_markdown(r.generalisation, o.arena);
    }
    return md;
}

}  // namespace

StudyResult run_study(const StudyOptions& o) {
    const Say say = [&](const std::string& line) {
        if (o.progress) o.progress(line);
    };
    const fs::path out(o.out_dir);
    fs::create_directories(out / "flights");
    fs::create_directories(out / "models");

    std::map<std::string, std::string> label;
    const Dataset all = fly_flights(o, out, label, say);
    const Split split = split_by_leg(all);
    say(log::cat(all.samples.size(), " samples; on legs: ", split.train.samples.size(), " training, ",
                 split.validation.samples.size(), " validation, ", split.test.samples.size(), " held out"));

    // 2. Train.
    Cores cores(std::max(1, o.jobs / o.threads));
    auto [naive, linear, deep, generalised] = train_models(o, split, out, cores);
    PhysicsModel physics(o.physics);
    write_text(out / "models" / "physics.yaml", physics::to_yaml(o.physics));

    // 3. Compare on held-out legs, overall and by altitude band; the regimes.
    StudyResult r;
    const std::vector<const ForceModel*> models{&physics, naive.get(), linear.get(), deep.get()};
    r.table = compare(models, split.test, o.arena);
    for (const double altitude : physics::GridOptions{}.altitudes_m)
        r.by_altitude.emplace_back(altitude, compare(models, split.test.in_altitude_band(altitude, o.arena.band_m),
                                                     arena_at(o.arena, altitude)));
    say("classifying the regimes");
    r.regimes = classify_regimes(sum_to_compare(*deep, *linear), *deep, split.test, physics::GridOptions{}.altitudes_m,
                                 RegimeOptions{}, o.stop);
    write_regimes(r.regimes, out.string());

    // 5. Maps (while the generalisation trains), then the tables.
    std::string maps_md;
    if (o.maps) {
        say("drawing maps");
        maps_md = draw_maps(o, out, models, all, label);
    }
    if (generalised.valid()) r.generalisation = generalised.get();
    std::vector<ComparisonRow> banded;  // for the CSV: the formation labelled with its band
    const std::string md = tables_markdown(o, r, banded) + maps_md;
    r.markdown_path = (out / "table.md").string();
    r.csv_path = (out / "table.csv").string();
    write_text(r.markdown_path, md);
    write_text(r.csv_path, to_csv(r.table) + to_csv(r.generalisation, false) + to_csv(banded, false));
    return r;
}

RegimesFiles write_regimes(const std::vector<RegimeRow>& rows, const std::string& dir, const RegimeOptions& o) {
    const fs::path out(dir);
    RegimesFiles f{rows, (out / "regimes.md").string(), (out / "regimes.csv").string(), (out / "regimes.png").string()};
    write_text(f.markdown_path, "# Regimes\n\n" + regimes_markdown(rows, o) + "\n![regimes](regimes.png)\n");
    write_text(f.csv_path, regimes_csv(rows));
    draw_regime_map(rows, f.png_path);
    return f;
}

RegimesFiles regimes_of_study(const std::string& study_dir, const RegimeOptions& o, std::stop_token stop) {
    const fs::path dir(study_dir), flights = dir / "flights", models = dir / "models";
    if (!fs::is_directory(input_status(flights.string(), "study flights")))
        throw InputError(log::cat(study_dir, ": no flights/ folder (not a dw-predictor study's output)"));
    Dataset all;
    std::vector<fs::path> folders;
    for (const auto& e : fs::directory_iterator(flights))
        if (e.is_directory()) folders.push_back(e.path());
    std::sort(folders.begin(), folders.end());
    for (const auto& f : folders) {
        throw_if_stopped(stop, "the regimes");
        all.append(load_dataset(f.string()));
    }
    const LearntModel linear = LearntModel::load((models / "learnt_linear.json").string());
    const LearntModel deep = LearntModel::load((models / "deep_sets.json").string());
    return write_regimes(classify_regimes(sum_to_compare(deep, linear), deep, split_by_leg(all).test,
                                          physics::GridOptions{}.altitudes_m, o, stop),
                         dir.string(), o);
}

}  // namespace dw::predictor
