#include "core/shutdown.hpp"

#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <cstdlib>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw {
namespace {
// The shared state is never destroyed: the detached signal thread may wake (a SIGINT arriving as
// main returns) after static destruction has begun, and a destroyed mutex or stop_source then
// crashed the process (status 139 instead of 0 or 130, seen once in CI on dw-predictor compare).
struct State {
    std::mutex mutex;
    std::condition_variable cv;
    bool requested = false;
    std::atomic<int> signal{0};
    std::once_flag once;
    std::function<void()> user_signal;
    std::stop_source stop;
};
State& state() {
    static State* s = new State;  // intentionally immortal (still reachable: not a leak)
    return *s;
}

void wait_for_signals(sigset_t set) {
    int interrupts = 0;
    for (;;) {
        int sig = 0;
        if (sigwait(&set, &sig) != 0) continue;
        if (sig == SIGUSR1) {
            std::function<void()> f;
            {
                std::lock_guard lock(state().mutex);
                f = state().user_signal;
            }
            if (f) f();
            continue;
        }
        // A second Ctrl-C ends the process at once (the escape hatch if a step never checks).
        if (sig == SIGINT && ++interrupts > 1) std::_Exit(kExitStopped);
        Shutdown::instance().request(sig);
    }
}
}  // namespace

Shutdown& Shutdown::instance() {
    static Shutdown s;
    return s;
}

Shutdown& Shutdown::install() {
    std::call_once(state().once, [] {
        sigset_t set;
        sigemptyset(&set);
        sigaddset(&set, SIGINT);
        sigaddset(&set, SIGTERM);
        sigaddset(&set, SIGUSR1);  // ignored unless someone asks for it (on_user_signal)
        pthread_sigmask(SIG_BLOCK, &set, nullptr);
        std::thread(wait_for_signals, set).detach();
    });
    return instance();
}

bool Shutdown::requested() const {
    std::lock_guard lock(state().mutex);
    return state().requested;
}

bool Shutdown::wait_for(std::chrono::nanoseconds d) const {
    std::unique_lock lock(state().mutex);
    return state().cv.wait_for(lock, d, [] { return state().requested; });
}

void Shutdown::request(int signal_number) {
    {
        std::lock_guard lock(state().mutex);
        if (!state().requested) state().signal = signal_number;
        state().requested = true;
    }
    state().cv.notify_all();
    state().stop.request_stop();
}

std::stop_token Shutdown::token() const { return state().stop.get_token(); }

void throw_if_stopped(const std::stop_token& stop, std::string_view what) {
    if (stop.stop_requested()) throw Stopped(log::cat("stopped during ", what));
}

bool wait_for(const std::stop_token& stop, std::chrono::nanoseconds d) {
    if (stop.stop_requested() || d <= std::chrono::nanoseconds::zero()) return stop.stop_requested();
    std::mutex m;
    std::condition_variable_any cv;
    std::unique_lock lock(m);
    cv.wait_for(lock, stop, d, [] { return false; });  // wakes at the stop request or after d
    return stop.stop_requested();
}

int Shutdown::signal_number() const { return state().signal; }

void Shutdown::on_user_signal(std::function<void()> f) {
    std::lock_guard lock(state().mutex);
    state().user_signal = std::move(f);
}

}  // namespace dw
