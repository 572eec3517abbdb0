#pragma once
// dw-probe's logic: publish deterministic samples on lab topics and echo them back with an
// integrity check, for every topic type. Used by the loopback session, the integration and
// multi-host tests, and by people checking a lab network by hand.
#include <chrono>
#include <cstdint>
#include <iosfwd>
#include <stop_token>
#include <string>
#include <vector>

#include "dds/participant.hpp"

namespace dw::probe {

struct PubOptions {
    std::vector<std::string> topics;  // suffixes
    std::uint64_t count = 10;         // samples per topic
    double rate_hz = 50.0;            // rounds per second (one sample per topic a round)
    int wait_readers = 0;             // wait until each writer has this many readers
    std::chrono::milliseconds wait_timeout{10000};
    dds::QosOverrides qos;
    bool quiet = false;
    // After publishing, keep the writers (and so the latched samples) alive this long;
    // negative = until shutdown is requested.
    std::chrono::milliseconds linger{0};
    std::stop_token stop;  // ends the publishing and the linger
};

// Publishes, then lingers; returns false when the readers did not show up in time (nothing is published then).
bool run_pub(dds::Participant& p, const PubOptions& o, std::ostream& out);

struct TopicResult {
    std::string topic;
    std::string type;
    std::string qos;
    std::uint64_t received = 0;  // probe samples (run id "probe")
    std::uint64_t other = 0;     // real lab traffic on the topic (not checked)
    std::uint64_t intact = 0;
    std::uint64_t corrupt = 0;
    std::uint64_t lost = 0;  // gaps in header.seq
    std::uint64_t first_seq = 0;
    std::uint64_t last_seq = 0;
    bool in_order = true;
    bool met = false;  // expectation reached
};

struct EchoOptions {
    std::vector<std::string> topics;
    std::uint64_t expect = 0;              // samples per topic before the echo ends (0 = run until stopped)
    std::int64_t expect_latched = -1;      // for latched (state) topics; -1 = same as expect
    std::chrono::milliseconds timeout{0};  // 0 = none
    dds::QosOverrides qos;
    bool quiet = false;
    std::stop_token stop;  // ends the echo (a report of what arrived so far)
};

struct EchoReport {
    std::vector<TopicResult> topics;
    bool timed_out = false;
    bool ok() const;  // every expectation met and nothing corrupt
    std::string to_json() const;
};

// Echoes until every expectation is met, the timeout passes or shutdown is requested.
EchoReport run_echo(dds::Participant& p, const EchoOptions& o, std::ostream& out);

void print_table(const EchoReport& report, std::ostream& out);

// Sends one experiment command (as the operator: dw-probe command abort) once a reader of
// experiment/command matched, and waits until it was acknowledged. Throws dw::RuntimeError when
// no reader appears within `wait`.
struct CommandOptions {
    msg::CommandKind kind = msg::CMD_ABORT;
    std::string reason;
    std::chrono::milliseconds wait{10000};
    // The process whose reader must have matched before the command is sent: the first reader to
    // match may be the recorder's, and a command written then never reaches the planner.
    std::string to{dds::role_name(dds::Role::planner)};
};
void send_command(dds::Participant& p, const CommandOptions& o, std::ostream& out);

}  // namespace dw::probe
