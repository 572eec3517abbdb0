// dw-lab: starts the lab's processes. For now: `dw-lab loopback`, a loopback DDS session in which
// every lab topic type is published, received, checked and shown.
#include <iostream>

#include "core/cli.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/process_cli.hpp"
#include "lab/loopback.hpp"

namespace {

int run(int argc, char** argv) {
    dw::Shutdown::install();
    dw::dds::ProcessCli cli("dw-lab: run the Downwash Lab's processes");
    CLI::App& app = cli.app();
    app.require_subcommand(1);

    dw::lab::LoopbackOptions lo;
    auto* loopback = app.add_subcommand("loopback", "publish, receive and show every lab topic type over loopback DDS");
    loopback->add_option("--count", lo.count, "samples per topic")->check(CLI::Range(1, 1000000));
    loopback->add_option("--rate", lo.rate_hz, "samples per second per topic")->check(CLI::Range(0.1, 10000.0));
    loopback->add_option("--timeout", lo.timeout_s, "seconds before giving up")->check(CLI::Range(1.0, 3600.0));
    loopback->add_option("--summary", lo.summary_path, "write the JSON summary here");
    loopback->add_flag("--quiet", lo.quiet, "show only the summary table");

    cli.parse(argc, argv);  // validates the DDS settings once, before any child starts
    lo.probe_path = dw::executable_dir() + "/dw-probe";
    lo.dds_args = cli.dds_args();
    return dw::lab::run_loopback(lo);
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-lab", [&] { return run(argc, argv); });
}
