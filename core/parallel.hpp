// Independent pieces of long work (flights flown and explained, seeds of a study) run on a few
// threads: each index is handed out once; the first exception stops handing out more and is
// rethrown once every thread has finished its piece.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace dw {

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

}  // namespace dw
