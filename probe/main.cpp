// dw-probe: list the lab's topics, publish test samples on them, echo them with an integrity check.
#include <unistd.h>

#include <fstream>
#include <iostream>

#include "dds/process_cli.hpp"
#include "core/command.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/wire_enums.hpp"
#include "probe/hostile.hpp"
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

// The topic selection and QoS overrides that pub and echo share.
struct TopicArgs {
    std::vector<std::string> topics;
    std::string reliability, durability;

    void add(CLI::App* sub) {
        sub->add_option("topics", topics, "topic suffixes (stand/wrench), full names, or all (default)");
        sub->add_option("--reliability", reliability, "override: reliable or best_effort");
        sub->add_option("--durability", durability, "override: volatile or transient_local");
    }
};

// What every dw-probe command is given: the DDS settings and its name in heartbeats.
struct ProbeTool : dw::cli::Command {
    ProbeTool(const dw::dds::ProcessCli& c, const std::string& n) : cli(c), name(n) {}
    const dw::dds::ProcessCli& cli;
    const std::string& name;
    CLI::App* sub = nullptr;
};

// The probe on the lab's DDS: its participant, its heartbeat saying it runs.
struct OnDds {
    OnDds(const ProbeTool& t) : participant(t.cli.dds(), t.name, t.cli.clock()), heartbeat(participant) {
        heartbeat.set_state(dw::msg::PROC_RUNNING);
    }
    dw::dds::Participant participant;
    dw::dds::Heartbeat heartbeat;
};

struct PubCommand final : ProbeTool {
    using ProbeTool::ProbeTool;
    TopicArgs topics;
    dw::probe::PubOptions options;
    double linger_s = 0.0;
    double wait_timeout_s = 10.0;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("pub", "publish deterministic samples on lab topics");
        topics.add(sub);
        sub->add_option("--count", options.count, "samples per topic")->check(dw::cli::in({1, 1e8}));
        sub->add_option("--rate", options.rate_hz, "rounds per second (one sample per topic each)")
            ->check(dw::cli::in({0, 1e5, "Hz"}));  // 0: as fast as the publisher can
        sub->add_option("--wait-readers", options.wait_readers, "wait for this many readers per topic first")
            ->check(dw::cli::in(dw::dds::kReadersRange));
        sub->add_option("--wait-timeout", wait_timeout_s, "seconds to wait for readers")
            ->check(dw::cli::in(dw::kTimeoutRange));
        sub->add_option("--linger", linger_s, "seconds to stay after publishing (latched topics), -1 = until stopped")
            ->check(dw::cli::in({-1, dw::kTimeoutRange.hi, "s"}));
        sub->add_flag("--quiet", options.quiet, "do not print each sample");
        return sub;
    }
    int run() override {
        options.topics = dw::dds::select_topics(topics.topics, cli.dds().ns);
        options.qos = qos_overrides(topics.reliability, topics.durability);
        OnDds dds(*this);
        options.wait_timeout = dw::to_millis(wait_timeout_s);
        options.linger = dw::to_millis(linger_s);
        options.stop = dw::Shutdown::instance().token();
        return dw::probe::run_pub(dds.participant, options, std::cout) ? 0 : dw::kExitRuntime;
    }
};

struct EchoCommand final : ProbeTool {
    using ProbeTool::ProbeTool;
    TopicArgs topics;
    dw::probe::EchoOptions options;
    double timeout_s = 0.0;
    std::string summary_path;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("echo", "print samples of lab topics and check their content");
        topics.add(sub);
        sub->add_option("--expect", options.expect, "end after this many intact samples per topic (0 = until stopped)")
            ->check(dw::cli::in({0, 1e8}));
        sub->add_option("--expect-latched", options.expect_latched,
                        "the same for latched topics (default, -1: --expect)")
            ->check(dw::cli::in({-1, 1e8}));
        sub->add_option("--timeout", timeout_s, "give up after this many seconds (exit 1; 0 = never)")
            ->check(dw::cli::in(dw::kTimeoutRange));
        sub->add_option("--summary", summary_path, "write a JSON summary here");
        sub->add_flag("--quiet", options.quiet, "print only the summary table");
        return sub;
    }
    int run() override {
        options.topics = dw::dds::select_topics(topics.topics, cli.dds().ns);
        options.qos = qos_overrides(topics.reliability, topics.durability);
        if (sub->count("--summary")) dw::require_writable_path(summary_path, "--summary");
        OnDds dds(*this);
        options.timeout = dw::to_millis(timeout_s);
        options.stop = dw::Shutdown::instance().token();
        const auto report = dw::probe::run_echo(dds.participant, options, std::cout);
        dw::probe::print_table(report, std::cout);
        if (!summary_path.empty()) dw::write_file(summary_path, report.to_json() + "\n");
        if (!report.ok())
            throw dw::RuntimeError("echo: not every topic received its samples intact (the table above says which)");
        return 0;
    }
};

struct CommandCommand final : ProbeTool {
    using ProbeTool::ProbeTool;
    dw::probe::CommandOptions options;
    std::string kind;

    CLI::App* add(CLI::App& app) override {
        const std::string kinds = dw::log::alternatives(dw::dds::command_names());
        sub = app.add_subcommand("command", "send the experiment a command as the operator: " + kinds);
        sub->add_option("kind", kind, kinds)->required();
        sub->add_option("--reason", options.reason, "why (in the planner's log and the experiment state)");
        sub->add_option("--to", options.to, "the process that must hear it (default planner)");
        return sub;
    }
    int run() override {
        const auto k = dw::dds::command_named(kind);
        if (!k) throw dw::InputError("command: " + dw::unknown_name_problem("kind", kind, dw::dds::command_names()));
        options.kind = *k;
        OnDds dds(*this);
        dw::probe::send_command(dds.participant, options, std::cout);
        return 0;
    }
};

struct HostileCommand final : ProbeTool {
    using ProbeTool::ProbeTool;
    std::vector<std::string> topics;
    dw::probe::HostileOptions options;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("hostile",
                                 "test tool: publish malformed samples on lab topics (bad encapsulation, truncated; "
                                 "absurd words on the sensor topics that command nothing)");
        sub->add_option("topics", topics, "topic suffixes (stand/wrench), full names, or all (default)");
        sub->add_option("--rate", options.rate_hz, "rounds per second (one sample per topic each)")
            ->check(dw::cli::in({0.1, 1e4, "Hz"}));
        sub->add_option("--seconds", options.seconds, "stop after this long (0 = until stopped)")
            ->check(dw::cli::in(dw::kTimeoutRange));
        sub->add_option("--seed", options.seed, "random seed (which words, how much is cut)")
            ->check(dw::cli::in(dw::kSeedRange));
        sub->add_option("--px4", options.px4_namespaces,
                        "PX4 namespaces (px4_1,...) whose output topics (vehicle_odometry, vehicle_status, "
                        "vehicle_command_ack; v1.15) get the same")
            ->delimiter(',');
        return sub;
    }
    int run() override {
        for (const auto& t : dw::dds::select_topics(topics, cli.dds().ns)) options.topics.push_back(t);
        options.stop = dw::Shutdown::instance().token();
        dw::probe::run_hostile(cli.dds(), options, std::cout);
        return 0;
    }
};

// `dw-probe list`: every lab topic with its type and QoS.
struct ListCommand final : ProbeTool {
    using ProbeTool::ProbeTool;
    CLI::App* add(CLI::App& app) override {
        return sub = app.add_subcommand("list", "list every lab topic with its type and QoS");
    }
    int run() override {
        dw::dds::topics::for_each([&](const auto& spec) {
            std::cout << "rt/" << cli.dds().ns << "/" << spec.suffix << "  " << spec.type_name << "  "
                      << dw::dds::to_string(spec.qos) << "  " << spec.description << "\n";
        });
        return 0;
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-probe: list the lab's DDS topics, publish test samples, echo and check them");
    CLI::App& app = cli.app();
    std::string name = "probe-" + std::to_string(::getpid());
    app.add_option("--name", name, "process name in heartbeats");
    app.require_subcommand(1);
    ListCommand list(cli, name);
    PubCommand pub(cli, name);
    EchoCommand echo(cli, name);
    CommandCommand command(cli, name);
    HostileCommand hostile(cli, name);
    return dw::cli::run_commands(app, {&list, &pub, &echo, &command, &hostile}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-probe", [&] { return run(argc, argv); });
}
