#pragma once
// Clean shutdown on SIGINT/SIGTERM. install() must run first in main(), before any thread
// (Fast DDS starts several) exists: it blocks the signals in every thread and waits for them in a
// dedicated one, so a signal never interrupts DDS code and main loops can wait on it.
#include <chrono>
#include <functional>

namespace dw {

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
    // Runs `f` (on the signal thread) at each SIGUSR1 — e.g. the recorder's pause/resume.
    void on_user_signal(std::function<void()> f);

private:
    Shutdown() = default;
};

}  // namespace dw
