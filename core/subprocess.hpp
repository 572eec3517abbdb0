#pragma once
// Starting and supervising child processes (the lab launcher, integration tests).
#include <sys/types.h>

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

namespace dw {

struct SpawnOptions {
    std::vector<std::string> argv;  // argv[0] is the program (a path, or a name on PATH)
    std::string stdout_path;        // "" = inherit
    std::string stderr_path;        // "" = inherit; may equal stdout_path
    std::vector<std::string> env;   // extra NAME=VALUE entries
    int niceness = 0;               // added to the child's nice value (its threads and children inherit it)
};

class Subprocess {
public:
    // Throws dw::RuntimeError when the program cannot be started.
    explicit Subprocess(const SpawnOptions& options);
    ~Subprocess();  // kills (SIGKILL) and reaps a child still running
    Subprocess(const Subprocess&) = delete;
    Subprocess& operator=(const Subprocess&) = delete;
    Subprocess(Subprocess&& other) noexcept;
    Subprocess& operator=(Subprocess&&) = delete;

    pid_t pid() const { return pid_; }
    void signal(int sig) const;
    // The exit status (exit code, or 128 + signal) once the child ended within d, else nullopt.
    std::optional<int> wait_for(std::chrono::milliseconds d);
    std::optional<int> poll();
    // SIGTERM, then SIGKILL after grace; returns the exit status.
    int stop(std::chrono::milliseconds grace = std::chrono::milliseconds(3000));
    bool running();

private:
    pid_t pid_ = -1;
    std::optional<int> status_;
};

// The last non-empty line of a log file (a failed child's own error), control bytes dropped, cut
// short when long; "" when there is none.
std::string last_line_of(const std::string& file);

// The directory holding the running executable (siblings live there).
std::string executable_dir();

// Runs a sibling lab executable (args[0], a name in executable_dir()) to completion with its
// output in log_file; stops it when `stop` is requested (dw::Stopped). Throws dw::RuntimeError in
// one line naming it, its status and the last line of its log (its own error) when it fails: the
// log may not outlive the failure (it is written into an output that is whole or not at all).
void run_sibling(const std::vector<std::string>& args, const std::string& log_file, const std::stop_token& stop);

// A sibling lab executable started in the background (this much nicer than its parent); finish()
// waits for it and fails as run_sibling does. One still running when this ends (its parent
// stopped or failed) is asked to stop (SIGTERM, then SIGKILL after kSiblingStopGrace), so that
// it removes its unfinished outputs as any stopped lab program does. Given the parent's stop, it is
// asked the moment a stop is requested, so its grace runs beside whatever else the parent stops.
inline constexpr std::chrono::milliseconds kSiblingStopGrace{5000};
class Sibling {
public:
    Sibling(const std::vector<std::string>& args, const std::string& log_file, int niceness = 0,
            const std::stop_token& stop = {});
    ~Sibling();
    Sibling(const Sibling&) = delete;
    Sibling& operator=(const Sibling&) = delete;
    void finish(const std::stop_token& stop);
    bool running();

private:
    void ask_to_stop();  // SIGTERM once: a second would end it at once, its outputs unremoved

    std::string name_, log_file_;
    std::mutex m_;  // the stop callback's thread and this one's waits
    Subprocess p_;
    bool asked_ = false;
    std::optional<std::stop_callback<std::function<void()>>> on_stop_;
};

}  // namespace dw
