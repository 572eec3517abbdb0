// Independent pieces of long work (flights flown and explained, seeds of a study) run on a few
// threads: each index is handed out once; the first exception stops handing out more and is
// rethrown once every thread has finished its piece. Cores lets work started on threads of its own
// take turns for the machine's cores.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <set>
#include <stop_token>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "core/numbers.hpp"
#include "core/shutdown.hpp"

namespace dw {

// The machine's cores as the standard library reports them; at least one (it may report 0).
inline int machine_cores() { return std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

// How many pieces of long work a tool may run at once (its --jobs): flights, trainings, explanations.
inline constexpr Range kJobsRange{1, 64};

// Calls task(i) for every i in [0, n) on `jobs` threads (at least one).
template <class Task>
void parallel_for(std::size_t n, int jobs, Task&& task) {
    std::atomic<std::size_t> next{0};
    std::mutex m;
    std::exception_ptr failed;
    auto work = [&] {
        for (std::size_t i; (i = next++) < n;) {
            try {
                task(i);
            } catch (...) {
                std::lock_guard lock(m);
                if (!failed) failed = std::current_exception();
                next = n;
            }
        }
    };
    {
        std::vector<std::jthread> pool;
        const auto threads =
            std::min<std::size_t>(static_cast<std::size_t>(std::max(1, jobs)), std::max<std::size_t>(n, 1));
        for (std::size_t j = 0; j < threads; ++j) pool.emplace_back(work);
    }
    if (failed) std::rethrow_exception(failed);
}

// A machine's cores shared by work started on threads of its own: work that comes first takes a core
// at once (beyond their number if it must: it is what others wait for); work that fills in waits
// until fewer than `count` are busy, the first come first. The work holds a Pass, and gives the
// core back when it is destroyed.
class Cores {
public:
    enum class Turn { now, when_free };
    explicit Cores(int count) : count_(std::max(1, count)) {}

    class Pass {
    public:
        Pass() = default;  // holds no core (work that is not counted)
        Pass(Pass&& o) noexcept : cores_(std::exchange(o.cores_, nullptr)) {}
        Pass& operator=(Pass&&) = delete;
        ~Pass() {
            if (cores_) cores_->give_back();
        }

    private:
        friend class Cores;
        explicit Pass(Cores* c) : cores_(c) {}
        Cores* cores_ = nullptr;
    };

    // Throws dw::Stopped ("stopped during <what>") if `stop` is requested while it waits.
    Pass take(Turn turn, const std::stop_token& stop, std::string_view what) {
        std::unique_lock lock(m_);
        bool in = true;
        if (turn == Turn::when_free) {
            const std::uint64_t ticket = next_++;
            waiting_.insert(ticket);
            in = cv_.wait(lock, stop, [&] { return busy_ < count_ && *waiting_.begin() == ticket; });
            waiting_.erase(ticket);
        }
        if (in) ++busy_;
        lock.unlock();
        cv_.notify_all();  // the next in line may go now: a core may still be free
        if (!in) throw_if_stopped(stop, what);
        return Pass(this);
    }
    int busy() const {
        const std::lock_guard lock(m_);
        return busy_;
    }
    int waiting() const {
        const std::lock_guard lock(m_);
        return static_cast<int>(waiting_.size());
    }

private:
    void give_back() {
        {
            const std::lock_guard lock(m_);
            --busy_;
        }
        cv_.notify_all();
    }

    mutable std::mutex m_;
    std::condition_variable_any cv_;
    const int count_;
    int busy_ = 0;
    std::uint64_t next_ = 0;
    std::set<std::uint64_t> waiting_;  // tickets of the work waiting, in order of arrival
};

}  // namespace dw
