// Unit tests of the core library's pieces that other tests do not reach on their own.
#include <gtest/gtest.h>

#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "core/errors.hpp"
#include "core/parallel.hpp"

using dw::Cores;

namespace {
void until(const std::function<bool()>& done) {  // no time limit: CTest's timeout is the limit
    while (!done()) std::this_thread::yield();
}
}  // namespace

TEST(Cores, FillInWorkWaitsForAFreeCoreFirstComeFirst) {
    Cores cores(1);
    std::optional<Cores::Pass> first(cores.take(Cores::Turn::now, {}, "first"));
    std::mutex m;
    std::vector<int> order;
    auto fill_in = [&](int id) {
        const auto pass = cores.take(Cores::Turn::when_free, {}, "filling in");
        const std::lock_guard lock(m);
        order.push_back(id);
    };
    std::jthread a(fill_in, 1);
    until([&] { return cores.waiting() == 1; });
    std::jthread b(fill_in, 2);
    until([&] { return cores.waiting() == 2; });
    {
        const auto beyond = cores.take(Cores::Turn::now, {}, "more");  // never waits, counts
        EXPECT_EQ(cores.busy(), 2);
    }
    EXPECT_EQ(cores.busy(), 1);
    EXPECT_EQ(cores.waiting(), 2);
    first.reset();
    a.join();
    b.join();
    EXPECT_EQ(order, (std::vector<int>{1, 2}));
    EXPECT_EQ(cores.busy(), 0);
}

TEST(Cores, FillInWorkGoesAtOnceWhileACoreIsFree) {
    Cores cores(2);
    const auto one = cores.take(Cores::Turn::now, {}, "one");
    const auto two = cores.take(Cores::Turn::when_free, {}, "two");
    EXPECT_EQ(cores.busy(), 2);
    EXPECT_EQ(cores.waiting(), 0);
}

TEST(Cores, AStopWhileWaitingIsStoppedAndTakesNoCore) {
    Cores cores(1);
    const auto held = cores.take(Cores::Turn::now, {}, "held");
    std::stop_source stop;
    std::string error;
    std::jthread waiter([&] {
        try {
            const auto pass = cores.take(Cores::Turn::when_free, stop.get_token(), "the wait");
        } catch (const dw::Stopped& e) {
            error = e.what();
        }
    });
    until([&] { return cores.waiting() == 1; });
    stop.request_stop();
    waiter.join();
    EXPECT_EQ(error, "stopped during the wait");
    EXPECT_EQ(cores.busy(), 1);
    EXPECT_EQ(cores.waiting(), 0);
}
