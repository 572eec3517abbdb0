// dw-lab: starts the lab's processes. `dw-lab demo` flies a whole simulated experiment and makes
// everything a researcher wants of it; `dw-lab run` starts a lab file's processes (here or on
// other hosts) and watches them; `dw-lab loopback` checks every topic type over loopback DDS.
#include <ctime>
#include <iostream>

#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/process_cli.hpp"
#include "lab/demo.hpp"
#include "lab/keys.hpp"
#include "lab/launcher.hpp"
#include "lab/loopback.hpp"
#include "lab/soak.hpp"

namespace {

// "20261125-081500": the default run folders' names.
std::string stamp() {
    char buf[32];
    const std::time_t t = std::time(nullptr);
    std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
    return std::string(buf);
}

// What every dw-lab command is given: the process's DDS settings (handed to what it starts).
struct LabTool : dw::cli::Command {
    explicit LabTool(const dw::dds::ProcessCli& c) : cli(c) {}
    const dw::dds::ProcessCli& cli;
    CLI::App* sub = nullptr;

    // A simulated lab run's: its folder (--out, else runs/<kind>-<time>), the DDS settings, the stop.
    template <class Options>
    void prepare_run(Options& o, const char* kind) const {
        if (sub->count("--out")) dw::require_output_dir(o.out_dir, "--out");
        if (o.out_dir.empty()) o.out_dir = dw::log::cat("runs/", kind, "-", stamp());
        o.dds_args = cli.dds_args();
        o.dds = cli.dds();
        o.stop = dw::Shutdown::instance().token();
    }
};

// `dw-lab keys create|list`: the DDS Security keystore.
struct KeysCommand final : LabTool {
    using LabTool::LabTool;
    dw::lab::KeysOptions options;
    CLI::App* create = nullptr;
    CLI::App* list = nullptr;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("keys", "the lab's DDS Security keystore: create (or add missing identities), list");
        sub->require_subcommand(1);
        create = sub->add_subcommand(
            "create", "a CA, one identity per process of --lab (or per role), signed governance and permissions");
        create->add_option("--keystore", options.keystore, "keystore folder (made if missing)")->required();
        create->add_option("--lab", options.lab_path,
                           "lab file: one identity per process, named as the process (default: one per role)");
        create->add_option("--days", options.days, "certificates and permissions expire after this many days")
            ->check(dw::cli::in({1, 36500}));
        list = sub->add_subcommand("list", "each identity, when it expires, and whether the keystore's CA signed it");
        list->add_option("--keystore", options.keystore, "keystore folder")->required();
        return sub;
    }
    int run() override {
        if (create->parsed()) return dw::lab::keys_create(options, std::cout);
        return dw::lab::keys_list(options.keystore, std::cout);
    }
};

// `dw-lab run`: a lab file's processes, watched until the experiment ends.
struct RunCommand final : LabTool {
    using LabTool::LabTool;
    std::string lab_path, run_dir;
    std::vector<std::string> var_args;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("run", "start a lab file's processes, watch them, stop them when the experiment ends");
        sub->add_option("--lab", lab_path, "lab file (downwash-lab/1), e.g. config/lab.sim.yaml")->required();
        sub->add_option("--run-dir", run_dir, "folder for logs and {run_dir} (default: runs/<time>)");
        sub->add_option("--var", var_args, "NAME=VALUE: set a lab-file variable (repeatable)");
        return sub;
    }
    int run() override {
        if (sub->count("--run-dir")) dw::require_output_dir(run_dir, "--run-dir");
        const auto lab = dw::lab::load_lab(lab_path);
        dw::lab::LaunchOptions o;
        o.run_dir = run_dir.empty() ? "runs/" + stamp() : run_dir;
        for (const auto& v : var_args) {
            const auto eq = v.find('=');
            if (eq == std::string::npos || eq == 0) throw dw::InputError("--var '" + v + "': expected NAME=VALUE");
            o.vars[v.substr(0, eq)] = v.substr(eq + 1);
        }
        o.dds_args = cli.dds_args();
        o.say = [](const std::string& s) { dw::log::progress(s); };
        o.stop = dw::Shutdown::instance().token();
        const auto r = dw::lab::launch(lab, o, cli.dds());
        for (const auto& p : r.printed) std::cout << "started elsewhere: " << p << "\n";
        std::cout << (r.phase.empty() ? "no experiment state seen" : r.phase) << ": " << r.legs_flown << " of "
                  << r.legs_total << " legs; logs in " << o.run_dir << "/logs\n";
        if (dw::Shutdown::instance().requested()) return 0;
        return r.succeeded() ? 0 : dw::kExitRuntime;
    }
};

// `dw-lab loopback`: every topic type over loopback DDS.
struct LoopbackCommand final : LabTool {
    using LabTool::LabTool;
    dw::lab::LoopbackOptions lo;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("loopback", "publish, receive and show every lab topic type over loopback DDS");
        sub->add_option("--count", lo.count, "samples per topic")->check(dw::cli::in({1, 1e6}));
        sub->add_option("--rate", lo.rate_hz, "samples per second per topic")->check(dw::cli::in({0.1, 1e4, "Hz"}));
        sub->add_option("--timeout", lo.timeout_s, "seconds before giving up")->check(dw::cli::in({1, 3600, "s"}));
        sub->add_option("--summary", lo.summary_path, "write the JSON summary here");
        sub->add_flag("--quiet", lo.quiet, "show only the summary table");
        return sub;
    }
    int run() override {
        if (sub->count("--summary")) dw::require_writable_path(lo.summary_path, "--summary");
        lo.probe_path = dw::executable_dir() + "/dw-probe";
        lo.dds_args = cli.dds_args();
        lo.stop = dw::Shutdown::instance().token();
        return dw::lab::run_loopback(lo);
    }
};

// `dw-lab demo`: a whole simulated experiment and everything a researcher wants of it.
struct DemoCommand final : LabTool {
    using LabTool::LabTool;
    dw::lab::DemoOptions o;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand(
            "demo", "fly a simulated experiment end to end: recording, models, table, maps, explained mismatch");
        sub->add_option("--out", o.out_dir, "run folder (default: runs/demo-<time>)");
        sub->add_flag("--quick", o.quick, "fewer legs and epochs (a smoke test, ~3 min)");
        sub->add_option("--jobs", o.jobs, "cores the study may use (default: every core)")
            ->check(dw::cli::in(dw::kJobsRange));
        sub->add_option("--viewer-port", o.viewer_port,
                        "dw-viewer's port while the experiments fly (default 8765; 0: any free one)")
            ->check(dw::cli::in(dw::kPortRange));
        return sub;
    }
    int run() override {
        prepare_run(o, "demo");
        return dw::lab::run_demo(o);
    }
};

// `dw-lab soak`: a long simulated run, every process's memory, CPU and losses sampled.
struct SoakCommand final : LabTool {
    using LabTool::LabTool;
    dw::lab::SoakOptions o;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand(
            "soak", "a long simulated lab run with every process's memory, CPU and losses sampled: no growth, no loss");
        sub->add_option("--minutes", o.minutes, "how long (default 3)")->check(dw::cli::in(dw::lab::kSoakMinutesRange));
        sub->add_option("--out", o.out_dir,
                        "folder for soak.md, soak.json, the charts and the run (default: runs/soak-<time>)");
        return sub;
    }
    int run() override {
        prepare_run(o, "soak");
        return dw::lab::run_soak(o);
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-lab: run the Downwash Lab's processes");
    CLI::App& app = cli.app();
    app.require_subcommand(1);
    LoopbackCommand loopback(cli);
    DemoCommand demo(cli);
    RunCommand run(cli);
    SoakCommand soak(cli);
    KeysCommand keys(cli);
    // parse validates the DDS settings once, before any child starts
    return dw::cli::run_commands(app, {&loopback, &demo, &run, &soak, &keys}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-lab", [&] { return run(argc, argv); });
}
