#pragma once
// Clean shutdown on SIGINT/SIGTERM. install() must run first in main(), before any thread
// (Fast DDS starts several) exists: it blocks the signals in every thread and waits for them in a
// dedicated one, so a signal never interrupts DDS code and main loops can wait on it. A second
// SIGINT (Ctrl-C pressed again) ends the process at once with exit code 130.
#include <chrono>
#include <functional>
#include <stop_token>
#include <string_view>

namespace dw {

// Throws dw::Stopped ("stopped during <what>") when `stop` has been requested. Long loops call it
// once per step, so a stop takes effect within one step.
void throw_if_stopped(const std::stop_token& stop, std::string_view what);
// Sleeps up to d; returns true as soon as `stop` is requested (at once if it already is). Library
// code waits on the stop token it was given, never on the process's Shutdown: the caller decides
// what stops it (main passes Shutdown::instance().token(), a test its own std::stop_source).
bool wait_for(const std::stop_token& stop, std::chrono::nanoseconds d);

class Shutdown {
public:
    static Shutdown& install();
    static Shutdown& instance();  // for code that only waits; install() must have run

    bool requested() const;
    // Sleeps up to d; returns true as soon as shutdown is requested.
    bool wait_for(std::chrono::nanoseconds d) const;
    void request(int signal_number = 0);
    // The signal that requested shutdown, 0 if requested by code or not at all.
    int signal_number() const;
    // Set when shutdown is requested: what long work takes (injected) to notice a stop.
    std::stop_token token() const;
    // Runs `f` (on the signal thread) at each SIGUSR1 — e.g. the recorder's pause/resume.
    void on_user_signal(std::function<void()> f);

private:
    Shutdown() = default;
};

}  // namespace dw
