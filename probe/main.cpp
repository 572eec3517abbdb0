// dw-probe: list the lab's topics, publish test samples on them, echo them with an integrity check.
#include <unistd.h>

#include <fstream>
#include <iostream>

#include "dds/process_cli.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/names.hpp"
#include "probe/probe.hpp"

namespace {

dw::dds::QosOverrides qos_overrides(const std::string& reliability, const std::string& durability) {
    dw::dds::QosOverrides q;
    if (reliability == "reliable") q.reliable = true;
    else if (reliability == "best_effort") q.reliable = false;
    else if (!reliability.empty())
        throw dw::InputError("--reliability: '" + reliability + "' (expected reliable or best_effort)");
    if (durability == "transient_local") q.transient_local = true;
    else if (durability == "volatile") q.transient_local = false;
    else if (!durability.empty())
        throw dw::InputError("--durability: '" + durability + "' (expected volatile or transient_local)");
    return q;
}

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-probe: list the lab's DDS topics, publish test samples, echo and check them");
    CLI::App& app = cli.app();
    std::string name = "probe-" + std::to_string(::getpid());
    app.add_option("--name", name, "process name in heartbeats");
    app.require_subcommand(1);

    auto* list = app.add_subcommand("list", "list every lab topic with its type and QoS");

    std::vector<std::string> topics;
    std::string reliability, durability;
    auto add_topic_options = [&](CLI::App* sub) {
        sub->add_option("topics", topics, "topic suffixes (stand/wrench), full names, or all (default)");
        sub->add_option("--reliability", reliability, "override: reliable or best_effort");
        sub->add_option("--durability", durability, "override: volatile or transient_local");
    };

    dw::probe::PubOptions pub;
    double linger_s = 0.0;
    double wait_timeout_s = 10.0;
    auto* pub_cmd = app.add_subcommand("pub", "publish deterministic samples on lab topics");
    add_topic_options(pub_cmd);
    pub_cmd->add_option("--count", pub.count, "samples per topic")->check(dw::cli::in({1, 1e8}));
    pub_cmd->add_option("--rate", pub.rate_hz, "rounds per second (one sample per topic each)")
        ->check(dw::cli::in({0, 1e5, "Hz"}));  // 0: as fast as the publisher can
    pub_cmd->add_option("--wait-readers", pub.wait_readers, "wait for this many readers per topic first")->check(dw::cli::in(dw::dds::kReadersRange));
    pub_cmd->add_option("--wait-timeout", wait_timeout_s, "seconds to wait for readers")->check(dw::cli::in(dw::kTimeoutRange));
    pub_cmd->add_option("--linger", linger_s, "seconds to stay after publishing (latched topics), -1 = until stopped")->check(dw::cli::in({-1, dw::kTimeoutRange.hi, "s"}));
    pub_cmd->add_flag("--quiet", pub.quiet, "do not print each sample");

    dw::probe::EchoOptions echo;
    double timeout_s = 0.0;
    std::string summary_path;
    auto* echo_cmd = app.add_subcommand("echo", "print samples of lab topics and check their content");
    add_topic_options(echo_cmd);
    echo_cmd->add_option("--expect", echo.expect, "end after this many intact samples per topic (0 = until stopped)")->check(dw::cli::in({0, 1e8}));
    echo_cmd->add_option("--expect-latched", echo.expect_latched, "the same for latched topics (default, -1: --expect)")->check(dw::cli::in({-1, 1e8}));
    echo_cmd->add_option("--timeout", timeout_s, "give up after this many seconds (exit 1; 0 = never)")->check(dw::cli::in(dw::kTimeoutRange));
    echo_cmd->add_option("--summary", summary_path, "write a JSON summary here");
    echo_cmd->add_flag("--quiet", echo.quiet, "print only the summary table");

    dw::probe::CommandOptions command;
    std::string command_kind;
    const std::string kinds = "abort, stop, pause, resume, calibrate or start";
    auto* command_cmd = app.add_subcommand("command", "send the experiment a command as the operator: " + kinds);
    command_cmd->add_option("kind", command_kind, kinds)->required();
    command_cmd->add_option("--reason", command.reason, "why (in the planner's log and the experiment state)");
    command_cmd->add_option("--to", command.to, "the process that must hear it (default planner)");

    cli.parse(argc, argv);
    if (command_cmd->parsed()) {
        const auto kind = dw::dds::command_named(command_kind);
        if (!kind) throw dw::InputError("command: unknown kind '" + command_kind + "' (expected " + kinds + ")");
        command.kind = *kind;
    }
    if (echo_cmd->count("--summary")) dw::require_writable_path(summary_path, "--summary");
    const dw::dds::DdsConfig& dds_config = cli.dds();

    if (list->parsed()) {
        dw::dds::topics::for_each([&](const auto& spec) {
            std::cout << "rt/" << dds_config.ns << "/" << spec.suffix << "  " << spec.type_name << "  "
                      << dw::dds::to_string(spec.qos) << "  " << spec.description << "\n";
        });
        return 0;
    }

    const auto selected = dw::dds::select_topics(topics, dds_config.ns);
    const auto qos = qos_overrides(reliability, durability);
    dw::dds::Participant participant(dds_config, name, cli.clock());
    dw::dds::Heartbeat heartbeat(participant);
    heartbeat.set_state(dw::msg::PROC_RUNNING);

    if (command_cmd->parsed()) {
        dw::probe::send_command(participant, command, std::cout);
        return 0;
    }
    if (pub_cmd->parsed()) {
        pub.topics = selected;
        pub.qos = qos;
        pub.wait_timeout = dw::to_millis(wait_timeout_s);
        pub.linger = dw::to_millis(linger_s);
        pub.stop = dw::Shutdown::instance().token();
        return dw::probe::run_pub(participant, pub, std::cout) ? 0 : dw::kExitRuntime;
    }

    echo.topics = selected;
    echo.qos = qos;
    echo.timeout = dw::to_millis(timeout_s);
    echo.stop = dw::Shutdown::instance().token();
    const auto report = dw::probe::run_echo(participant, echo, std::cout);
    dw::probe::print_table(report, std::cout);
    if (!summary_path.empty()) {
        dw::write_file(summary_path, report.to_json() + "\n");
    }
    if (!report.ok()) throw dw::RuntimeError("echo: not every topic received its samples intact (the table above says which)");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-probe", [&] { return run(argc, argv); });
}
