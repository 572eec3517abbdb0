// dw-import: another lab's recordings to a flight folder. One subcommand per source format.
#include <iostream>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "importer/importer.hpp"

namespace {

int run(int argc, char** argv) {
    CLI::App app{"dw-import: bring another lab's flight logs into a flight folder (downwash-flight/1)"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    app.require_subcommand(1);
    std::vector<std::string> logs;
    std::string out;
    dw::importer::ImportOptions o;
    std::vector<std::pair<CLI::App*, const dw::importer::Importer*>> commands;
    for (const auto* im : dw::importer::importers()) {
        auto* sub = app.add_subcommand(std::string(im->name()), std::string(im->description()));
        sub->add_option("logs", logs, "the log files of one trial, one per vehicle")->required();
        sub->add_option("--out", out, "flight folder to write")->required();
        sub->add_option("--sufferer", o.sufferer,
                        "the vehicle whose residual force is the wrench (default: the lowest)");
        commands.emplace_back(sub, im);
    }
    dw::cli::parse(app, argc, argv);
    dw::log::set_level(dw::log::parse_level(base.log_level));
    dw::require_output_dir(out, "--out");
    if (std::filesystem::exists(out))
        throw dw::InputError("--out " + out + ": exists already (a flight folder is written whole, once)");
    o.warn = [](const std::string& w) { dw::log::warn(w); };
    o.stop = dw::Shutdown::instance().token();
    for (const auto& [sub, im] : commands) {
        if (!sub->parsed()) continue;
        const auto f = im->import(logs, o);
        dw::flight::write_flight(f, out);
        std::cout << "wrote " << out << ": sufferer " << f.meta.sufferer << ", " << f.meta.neighbours.size()
                  << " neighbour(s), " << f.wrench.size() << " wrench samples, " << f.poses.size() << " poses\n";
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-import", [&] { return run(argc, argv); });
}
