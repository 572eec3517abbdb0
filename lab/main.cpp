// dw-lab: starts the lab's processes. For now: `dw-lab loopback`, a loopback DDS session in which
// every lab topic type is published, received, checked and shown.
#include <iostream>

#include "core/cli.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/config.hpp"
#include "lab/loopback.hpp"

namespace {

int run(int argc, char** argv) {
    dw::Shutdown::install();
    CLI::App app{"dw-lab: run the Downwash Lab's processes"};
    dw::cli::BaseOptions base;
    dw::dds::DdsCliOptions dds_cli;
    dw::cli::configure(app, base);
    dw::dds::add_cli_options(app, dds_cli);
    app.require_subcommand(1);

    dw::lab::LoopbackOptions lo;
    auto* loopback = app.add_subcommand("loopback", "publish, receive and show every lab topic type over loopback DDS");
    loopback->add_option("--count", lo.count, "samples per topic")->check(CLI::Range(1, 1000000));
    loopback->add_option("--rate", lo.rate_hz, "samples per second per topic")->check(CLI::Range(0.1, 10000.0));
    loopback->add_option("--timeout", lo.timeout_s, "seconds before giving up")->check(CLI::Range(1.0, 3600.0));
    loopback->add_option("--summary", lo.summary_path, "write the JSON summary here");
    loopback->add_flag("--quiet", lo.quiet, "show only the summary table");

    dw::cli::parse(app, argc, argv);
    dw::log::set_level(dw::log::parse_level(base.log_level));
    const dw::ConfigFile config = base.config_path.empty() ? dw::ConfigFile() : dw::ConfigFile::load(base.config_path);
    const dw::dds::DdsConfig dds = dw::dds::resolve(dds_cli, config);  // validated here, once

    lo.probe_path = dw::executable_dir() + "/dw-probe";
    lo.dds_args = {"--domain", std::to_string(dds.domain), "--profile", dw::dds::to_string(dds.profile),
                   "--transport", dw::dds::to_string(dds.transport), "--namespace", dds.ns,
                   "--log-level", base.log_level};
    for (const auto& peer : dds.initial_peers) lo.dds_args.insert(lo.dds_args.end(), {"--peer", peer});
    if (!dds.discovery_server.empty()) lo.dds_args.insert(lo.dds_args.end(), {"--discovery-server", dds.discovery_server});
    return dw::lab::run_loopback(lo);
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-lab", [&] { return run(argc, argv); });
}
