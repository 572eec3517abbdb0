#include "lab/launcher.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"
#include "dds/heartbeat.hpp"
#include "dds/roles.hpp"
#include "dds/wire_enums.hpp"
#include "dds/participant.hpp"
#include "dds/time.hpp"
#include "lab/resources.hpp"

namespace dw::lab {

std::string progress_bar(unsigned flown, unsigned total, double progress, double eta_s, int width) {
    const double f = std::clamp(progress, 0.0, 1.0);
    const int fill = static_cast<int>(std::lround(f * width));
    std::ostringstream s;
    s << "[" << std::string(static_cast<std::size_t>(fill), '#')
      << std::string(static_cast<std::size_t>(width - fill), '.') << "] " << flown << "/" << total << " legs  "
      << static_cast<int>(std::lround(f * 100)) << " %";
    if (eta_s >= 0) {
        const int e = static_cast<int>(std::lround(eta_s));
        char buf[32];
        std::snprintf(buf, sizeof buf, "  ETA %d:%02d", e / 60, e % 60);
        s << buf;
    }
    return s.str();
}

namespace {

// Under DDS Security, the gap between two process starts. Fast DDS 2.9.1's authentication
// handshake can fail for good between participants that start at the same instant: six secure
// lab processes started at once left a pair unmatched after 60 s in 5 of 13 rounds, 300 ms
// apart in none of 8 (dw-bench-security, docs/BENCHMARKS.md).
constexpr std::chrono::milliseconds kSecureStartGap{300};

std::string quoted(const std::vector<std::string>& argv) {
    std::string s;
    for (const auto& a : argv) {
        const bool plain = !a.empty() && a.find_first_of(" \t'\"$\\{}") == std::string::npos;
        s += (s.empty() ? "" : " ") + (plain ? a : "'" + a + "'");
    }
    return s;
}

struct Running {
    ProcessSpec spec;
    std::vector<std::string> argv;
    std::string log;
    std::unique_ptr<Subprocess> proc;  // null: started elsewhere (printed)
    std::optional<int> ended;
    int restarts = 0;
    bool recorder = false;                  // dw-recorder record
    std::vector<std::string> restart_args;  // appended to argv when restarted
};

// A restarted recorder keeps what its predecessor wrote: a new file, the old one recovered.
constexpr std::string_view kRecorderKeepExisting = "--keep-existing";

bool is_recorder(const std::vector<std::string>& args) {
    return dds::role_of_executable(args[0]) == dds::Role::recorder && args.size() > 1 && args[1] == "record";
}

// A restarted process joins with a participant id of its own, counted down from the top of the
// range (auto ids are the lowest free), never its predecessor's (dds::DdsConfig::participant_id
// says why); a restarted recorder keeps what its predecessor wrote.
std::vector<std::string> restart_args(const Running& r, int participant_id) {
    std::vector<std::string> a{"--participant-id", std::to_string(participant_id)};
    if (r.recorder) a.emplace_back(kRecorderKeepExisting);
    return a;
}

// When the lab records, every other process holds its sensor topics' first samples until the
// recorder's readers matched (dds::DdsConfig::await_readers), unless the flags already say whom to await.
std::vector<std::string> await_args(const LabFile& lab, const std::map<std::string, std::string>& vars,
                                    const std::vector<std::string>& dds_args) {
    if (std::find(dds_args.begin(), dds_args.end(), "--await-readers") != dds_args.end()) return {};
    for (const auto& p : lab.processes)
        if (is_recorder(expand(p, vars))) return {"--await-readers", std::string(dds::role_name(dds::Role::recorder))};
    return {};
}

// Every command built first: a bad variable stops the run before anything starts.
std::deque<Running> build_commands(const LabFile& lab, const LaunchOptions& o) {
    namespace fs = std::filesystem;
    std::map<std::string, std::string> vars = lab.vars;
    for (const auto& [k, v] : o.vars) vars[k] = v;
    vars["run_dir"] = o.run_dir;
    const std::vector<std::string> await = await_args(lab, vars, o.dds_args);
    std::deque<Running> procs;
    for (const auto& p : lab.processes) {
        const HostSpec& host = lab.hosts.at(p.host);
        auto args = expand(p, vars);
        const std::string bin = host.bin.empty() ? executable_dir() : host.bin;
        std::vector<std::string> argv = host.launch;
        argv.push_back(bin + "/" + args[0]);
        argv.insert(argv.end(), args.begin() + 1, args.end());
        argv.insert(argv.end(), o.dds_args.begin(), o.dds_args.end());
        if (!is_recorder(args)) argv.insert(argv.end(), await.begin(), await.end());
        if (std::find(o.dds_args.begin(), o.dds_args.end(), "--security") != o.dds_args.end())
            argv.insert(argv.end(),
                        {"--identity", p.name});  // each process its own identity (dw-lab keys create --lab)
        procs.push_back({p,
                         argv,
                         (fs::path(o.run_dir) / "logs" / (p.name + ".log")).string(),
                         nullptr,
                         std::nullopt,
                         0,
                         is_recorder(args),
                         {}});
    }
    return procs;
}

// The process's clock against the reference (the recorder's), as its heartbeat states it:
// "+12.31 ms ±0.08", or "not measured" (no recorder yet).
std::string clock_text(const msg::ProcessStatus& s) {
    if (!(s.clock_uncertainty_s() >= 0)) return "not measured";
    char text[64];
    std::snprintf(text, sizeof text, "%+8.2f ms ±%.2f", s.clock_offset_s() * 1e3, s.clock_uncertainty_s() * 1e3);
    return text;
}

// Who sent a process's heartbeats: "open" when the launcher joined without a keystore; under DDS
// Security "auth" when the participant that sent it authenticated as the process's own identity,
// "auth?" while its identity is not yet known, and "AS <identity>" when another lab identity
// speaks for the process (any lab identity may publish heartbeats: the permissions cannot tell).
std::string auth_text(bool secure, const std::string& identity, const std::string& process) {
    if (!secure) return "open";
    if (identity.empty()) return "auth?";
    return identity == process ? "auth" : "AS " + identity;
}

// One status line per process (from its heartbeat) and the experiment's progress (`secure`: the
// launcher itself joined with a keystore).
std::string status_text(const std::deque<Running>& procs, const dds::PeerMonitor& peers,
                        const std::optional<msg::ExperimentState>& state, bool secure) {
    std::ostringstream s;
    for (const auto& r : procs) {
        char line[256];
        const auto st = peers.last(r.spec.name);
        std::string where = r.proc ? log::cat("pid ", r.proc->pid()) : "elsewhere";
        if (r.ended) where = log::cat("exited ", *r.ended);
        if (st) {
            double out_hz = 0, in_hz = 0;
            unsigned long long lost = 0;
            for (const auto& t : st->rates()) {
                (t.outgoing() ? out_hz : in_hz) += t.rate_hz();
                lost += t.lost();
            }
            std::snprintf(line, sizeof line,
                          "  %-14s %-9s %-10s @%-8s %-5s out %7.1f Hz  in %7.1f Hz  lost %-6llu clock %s%s%s",
                          r.spec.name.c_str(), dds::process_state_name(st->state()), where.c_str(), r.spec.host.c_str(),
                          auth_text(secure, peers.identity(r.spec.name), r.spec.name).c_str(), out_hz, in_hz, lost,
                          clock_text(*st).c_str(), st->message().empty() ? "" : "  ", st->message().c_str());
        } else {
            const auto role = dds::role_of_executable(r.spec.run.front());
            const bool reads_only = role && dds::has(dds::kReadOnlyRoles, *role);  // publishes no heartbeat
            std::snprintf(line, sizeof line, "  %-14s %-9s %-10s @%-8s %s", r.spec.name.c_str(), "-", where.c_str(),
                          r.spec.host.c_str(), reads_only ? "(reads only: no heartbeat)" : "(no heartbeat yet)");
        }
        s << line << "\n";
    }
    if (state)
        s << "  experiment     " << dds::phase_name(state->phase()) << "  "
          << progress_bar(state->phase() == msg::PHASE_DONE ? state->leg_count()
                                                            : static_cast<unsigned>(std::max(0, state->leg_index())),
                          state->leg_count(), state->progress(),
                          state->phase() == msg::PHASE_DONE ? -1.0 : state->eta_s())
          << "\n";
    return s.str();
}

// One row per running process of this host: its memory, CPU time and losses (logs/resources.csv).
void log_resources(std::ofstream& out, const std::deque<Running>& procs, const dds::PeerMonitor& peers, double t_s) {
    for (const auto& r : procs) {
        if (!r.proc || r.ended) continue;
        const auto usage = usage_of(r.proc->pid());
        if (!usage) continue;
        std::uint64_t lost = 0;
        if (const auto st = peers.last(r.spec.name))
            for (const auto& t : st->rates()) lost += t.lost();
        out << to_csv_line({t_s, r.spec.name, r.proc->pid(), *usage, lost});
    }
    out.flush();
}

// Stop in reverse order, so the recorder (started early) sees the others' last words.
void stop_all(std::deque<Running>& procs, double grace_s, const std::function<void(const std::string&)>& say) {
    for (auto it = procs.rbegin(); it != procs.rend(); ++it)
        if (it->proc && !it->ended) it->proc->signal(SIGINT);
    for (auto it = procs.rbegin(); it != procs.rend(); ++it) {
        if (!it->proc || it->ended) continue;
        const int st = it->proc->stop(std::chrono::milliseconds(static_cast<long>(grace_s * 1000)));
        say(log::cat("stopped ", it->spec.name, " (status ", st, ")"));
    }
}

using Say = std::function<void(const std::string&)>;

void start_process(Running& r) {
    std::vector<std::string> argv = r.argv;
    argv.insert(argv.end(), r.restart_args.begin(), r.restart_args.end());
    r.proc = std::make_unique<Subprocess>(SpawnOptions{argv, r.log, r.log, {}});
    r.ended.reset();
}

// Each process started here, or its command printed for a host the launcher cannot reach.
void start_all(std::deque<Running>& procs, const LabFile& lab, bool secure, const std::stop_token& stop,
               LaunchResult& R, const Say& say) {
    for (auto& r : procs) {
        const HostSpec& host = lab.hosts.at(r.spec.host);
        if (r.spec.host != "local" && host.launch.empty()) {
            R.printed.push_back(log::cat(r.spec.host, ": ", quoted(r.argv)));
            say(log::cat("start on ", r.spec.host, ":  ", quoted(r.argv)));
            continue;
        }
        if (secure && &r != &procs.front()) wait_for(stop, kSecureStartGap);
        start_process(r);
        say(log::cat("started ", r.spec.name, " on ", r.spec.host, " (pid ", r.proc->pid(), "): ", quoted(r.argv),
                     "  → ", r.log));
    }
}

// A process (not the experiment) ended: restarted when its lab file says so, up to 3 times, each
// time with a participant id no first start has (counted down; refused once they run out).
void on_exit(Running& r, int status, std::size_t lab_size, int& next_participant_id, LaunchResult& R, const Say& say) {
    const std::string said = status == 0 ? "" : last_line_of(r.log);  // its own error, when it failed
    say(log::cat(r.spec.name, " exited with status ", status, said.empty() ? "" : ": ", said, " (log: ", r.log, ")"));
    if (r.spec.restart != Restart::on_failure || status == 0 || r.restarts >= 3) return;
    if (next_participant_id < static_cast<int>(lab_size)) {
        say(log::cat("not restarting ", r.spec.name, ": no fresh DDS participant id left (ids below ", lab_size,
                     " are the lab's first starts)"));
        return;
    }
    ++r.restarts;
    ++R.restarts[r.spec.name];
    r.restart_args = restart_args(r, next_participant_id--);
    say(log::cat("restarting ", r.spec.name, " (", r.restarts, " of 3) with ", quoted(r.restart_args)));
    start_process(r);
}

void note_final_state(const std::optional<msg::ExperimentState>& state, LaunchResult& R) {
    if (!state) return;
    R.phase = dds::phase_name(state->phase());
    R.done = state->phase() == msg::PHASE_DONE;
    R.legs_total = state->leg_count();
    R.legs_flown =
        state->phase() == msg::PHASE_DONE ? state->leg_count() : static_cast<unsigned>(std::max(0, state->leg_index()));
}

// The status lines on stderr: on a terminal each redraw replaces the last.
class StatusLines {
public:
    explicit StatusLines(bool tty) : tty_(tty) {}
    void show(const std::string& text) {
        if (tty_) {
            for (int i = 0; i < drawn_; ++i) std::fputs("\033[F\033[K", stderr);
            drawn_ = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
        }
        std::fputs(text.c_str(), stderr);
        std::fflush(stderr);
    }
    std::chrono::seconds period() const { return tty_ ? std::chrono::seconds(1) : std::chrono::seconds(10); }

private:
    bool tty_;
    int drawn_ = 0;
};

// logs/resources.csv with its header; a folder that cannot take it is said once, and the run goes on.
std::ofstream open_resources(const std::string& run_dir, const std::function<void(const std::string&)>& say) {
    std::ofstream resources(std::filesystem::path(run_dir) / "logs" / kResourceFile);
    if (!(resources << kResourceHeader << "\n"))
        say(log::cat("cannot write ", run_dir, "/logs/", kResourceFile, ": no resource samples this run"));
    return resources;
}

}  // namespace

LaunchResult launch(const LabFile& lab, const LaunchOptions& o, const dds::DdsConfig& monitor) {
    const std::function<void(const std::string&)> say = [&](const std::string& s) {
        if (o.say) o.say(s);
    };
    std::filesystem::create_directories(std::filesystem::path(o.run_dir) / "logs");
    std::deque<Running> procs = build_commands(lab, o);

    LaunchResult R;
    dds::DdsConfig self = monitor;
    if (!self.security.empty() && self.identity.empty())
        self.identity = std::string(dds::role_name(dds::Role::launcher));
    dds::Participant participant(self, "lab");
    dds::PeerMonitor peers(participant, [&](const dds::PeerEvent& e) {
        say(log::cat(e.process, e.kind == dds::PeerEvent::Kind::appeared ? " is up" : " is gone: " + e.reason));
    });
    std::mutex m;
    std::optional<msg::ExperimentState> state;
    dds::Reader<msg::ExperimentState> states(participant, dds::topics::experiment_state,
                                             [&](const msg::ExperimentState& s, const dds::SampleMeta&) {
                                                 std::lock_guard lock(m);
                                                 state = s;
                                             });

    int next_participant_id = dds::kMaxParticipantId;
    start_all(procs, lab, !self.security.empty(), o.stop, R, say);

    StatusLines lines(o.live && ::isatty(STDERR_FILENO));
    auto draw = [&] {
        std::optional<msg::ExperimentState> now_state;
        {
            std::lock_guard lock(m);
            now_state = state;
        }
        lines.show(status_text(procs, peers, now_state, !self.security.empty()));
    };

    Running* experiment = nullptr;
    for (auto& r : procs)
        if (r.spec.experiment) experiment = &r;
    auto last_draw = std::chrono::steady_clock::now() - std::chrono::hours(1);
    const auto launched = std::chrono::steady_clock::now();
    auto last_resources = launched - std::chrono::hours(1);
    std::ofstream resources = open_resources(o.run_dir, say);
    while (!o.stop.stop_requested()) {
        for (auto& r : procs) {
            if (!r.proc || r.ended) continue;
            if (auto st = r.proc->poll()) {
                r.ended = st;
                if (&r == experiment) break;
                on_exit(r, *st, procs.size(), next_participant_id, R, say);
            }
        }
        if (experiment && experiment->ended) break;
        const auto now = std::chrono::steady_clock::now();
        if (now - last_resources >= std::chrono::duration<double>(kResourcePeriodS)) {
            log_resources(resources, procs, peers, std::chrono::duration<double>(now - launched).count());
            last_resources = now;
        }
        if (now - last_draw >= lines.period()) {
            draw();
            last_draw = now;
        }
        wait_for(o.stop, std::chrono::milliseconds(100));
    }
    draw();
    if (experiment && experiment->ended) {
        R.experiment_status = *experiment->ended;
        say(log::cat(experiment->spec.name, " ended with status ", R.experiment_status));
    } else {
        say("stopping the lab (interrupted)");
    }
    {
        std::lock_guard lock(m);
        note_final_state(state, R);
    }
    stop_all(procs, o.stop_grace_s, say);
    return R;
}

}  // namespace dw::lab
