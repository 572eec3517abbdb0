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
std::mutex g_mutex;
std::condition_variable g_cv;
bool g_requested = false;
std::atomic<int> g_signal{0};
std::once_flag g_once;
std::function<void()> g_user_signal;
std::stop_source g_stop;

void wait_for_signals(sigset_t set) {
    int interrupts = 0;
    for (;;) {
        int sig = 0;
        if (sigwait(&set, &sig) != 0) continue;
        if (sig == SIGUSR1) {
            std::function<void()> f;
            {
                std::lock_guard lock(g_mutex);
                f = g_user_signal;
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
    std::call_once(g_once, [] {
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
    std::lock_guard lock(g_mutex);
    return g_requested;
}

bool Shutdown::wait_for(std::chrono::nanoseconds d) const {
    std::unique_lock lock(g_mutex);
    return g_cv.wait_for(lock, d, [] { return g_requested; });
}

void Shutdown::request(int signal_number) {
    {
        std::lock_guard lock(g_mutex);
        if (!g_requested) g_signal = signal_number;
        g_requested = true;
    }
    g_cv.notify_all();
    g_stop.request_stop();
}

std::stop_token Shutdown::token() const { return g_stop.get_token(); }

void throw_if_stopped(const std::stop_token& stop, std::string_view what) {
    if (stop.stop_requested()) throw Stopped(log::cat("stopped during ", what));
}

int Shutdown::signal_number() const { return g_signal; }

void Shutdown::on_user_signal(std::function<void()> f) {
    std::lock_guard lock(g_mutex);
    g_user_signal = std::move(f);
}

}  // namespace dw
