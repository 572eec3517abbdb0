// dw-import: another lab's recordings to a flight folder. One subcommand per source format.
#include <filesystem>
#include <iostream>

#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "importer/importer.hpp"
#include "importer/neural_swarm.hpp"

namespace {

namespace fs = std::filesystem;

// `dw-import neural-swarm-collection DIR --out DIR`: every trial of a collection, one flight folder
// each (the lowest vehicle the sufferer). A trial of one vehicle is a flight without neighbours
// (what its residual does with nobody near: dw-explain calibrate reports it).
// A trial that cannot be imported is said in one line and the others go on; then exit 2.
int import_collection(const std::string& dir, const std::string& out, const dw::importer::ImportOptions& o) {
    const auto trials = dw::importer::collection_trials(dir);
    fs::create_directories(out);
    std::size_t written = 0, failed = 0;
    for (const auto& t : trials) {
        dw::throw_if_stopped(o.stop, "the import");
        const std::string folder = (fs::path(out) / t.name).string();
        try {
            if (fs::exists(folder)) throw dw::InputError(folder + ": exists already");
            const auto f = dw::importer::neural_swarm_importer().import(t.logs, o);
            dw::flight::write_flight(f, folder);
            std::cout << "wrote " << folder << ": sufferer " << f.meta.sufferer << ", " << f.meta.neighbours.size()
                      << " neighbour(s)\n";
            ++written;
        } catch (const dw::InputError& e) {
            dw::log::error(t.name, ": ", e.what());
            ++failed;
        }
    }
    std::cout << written << " flights written to " << out
              << (failed ? dw::log::cat(", ", failed, " trials failed") : "") << "\n";
    return failed ? 2 : 0;
}

void add_thrust_lag(CLI::App& sub, dw::importer::ImportOptions& o) {
    sub.add_option(
           "--thrust-lag", o.thrust_lag,
           dw::log::cat("the thrust's first-order lag per sample, T_lag <- a T_lag + (1 - a) T (default: the authors' ",
                        dw::importer::kAuthorsThrustLag, ")"))
        ->check(dw::cli::in(dw::importer::kThrustLagRange));
}

// What every import does before its own work: the output folder checked, warnings and the stop.
void prepare(const std::string& out, dw::importer::ImportOptions& o) {
    dw::require_output_dir(out, "--out");
    o.warn = [](const std::string& w) { dw::log::warn(w); };
    o.stop = dw::Shutdown::instance().token();
}

// `dw-import <format>`: one trial's logs in one importer's format.
struct ImportCommand final : dw::cli::Command {
    explicit ImportCommand(const dw::importer::Importer& i) : im(i) {}
    const dw::importer::Importer& im;
    std::vector<std::string> logs;
    std::string out;
    dw::importer::ImportOptions o;

    CLI::App* add(CLI::App& app) override {
        auto* sub = app.add_subcommand(std::string(im.name()), std::string(im.description()));
        sub->add_option("logs", logs, "the log files of one trial, one per vehicle")->required();
        sub->add_option("--out", out, "flight folder to write")->required();
        sub->add_option("--sufferer", o.sufferer,
                        "the vehicle whose residual force is the wrench (default: the lowest)");
        add_thrust_lag(*sub, o);
        return sub;
    }
    int run() override {
        prepare(out, o);
        if (std::filesystem::exists(out))
            throw dw::InputError("--out " + out + ": exists already (a flight folder is written whole, once)");
        const auto f = im.import(logs, o);
        dw::flight::write_flight(f, out);
        std::cout << "wrote " << out << ": sufferer " << f.meta.sufferer << ", " << f.meta.neighbours.size()
                  << " neighbour(s), " << f.wrench.size() << " wrench samples, " << f.poses.size() << " poses\n";
        return 0;
    }
};

// `dw-import neural-swarm-collection`: every trial of a collection folder.
struct CollectionCommand final : dw::cli::Command {
    std::string collection, out;
    dw::importer::ImportOptions o;

    CLI::App* add(CLI::App& app) override {
        auto* sub = app.add_subcommand("neural-swarm-collection",
                                       "every trial of a Neural-Swarm collection folder, one flight folder each");
        sub->add_option("dir", collection, "the collection (e.g. .../datacollection21_06_16_2020)")->required();
        sub->add_option("--out", out, "folder for the flight folders (one per trial)")->required();
        add_thrust_lag(*sub, o);
        return sub;
    }
    int run() override {
        prepare(out, o);
        return import_collection(collection, out, o);
    }
};

int run(int argc, char** argv) {
    CLI::App app{"dw-import: bring another lab's flight logs into a flight folder (downwash-flight/1)"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    app.require_subcommand(1);
    std::vector<ImportCommand> formats;
    for (const auto* im : dw::importer::importers()) formats.emplace_back(*im);
    CollectionCommand collection;
    std::vector<dw::cli::Command*> commands;
    for (auto& f : formats) commands.push_back(&f);
    commands.push_back(&collection);
    return dw::cli::run_commands(app, commands, [&] {
        dw::cli::parse(app, argc, argv);
        dw::log::set_level(dw::log::parse_level(base.log_level));
    });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-import", [&] { return run(argc, argv); });
}
