#include "stand_agent/hx711.hpp"

namespace dw::stand {

std::int32_t sign_extend_24(std::uint32_t word) {
    word &= 0xFFFFFF;
    return (word & 0x800000) ? static_cast<std::int32_t>(word) - 0x1000000 : static_cast<std::int32_t>(word);
}

bool Hx711Driver::wait_ready(std::uint8_t mask, Hx711Sample& s) {
    const Nanos deadline = lines_.now_ns() + options_.ready_timeout_ns;
    for (;;) {
        const std::uint8_t busy = lines_.read_data() & mask;  // DOUT high: not ready
        if (busy == 0) return true;
        if (lines_.now_ns() >= deadline) {
            s.not_ready |= busy;
            return false;
        }
        lines_.sleep_for_ns(options_.poll_ns);
    }
}

void Hx711Driver::pulses(std::uint8_t mask, std::array<std::uint32_t, kChips>* words, Hx711Sample& s) {
    const int n = static_cast<int>(options_.gain);
    for (int p = 0; p < n; ++p) {
        // Timed from before the edge: a thread pre-empted right after raising the clock, before
        // it could read the time, must still count the stall (the phase is over-timed by one call).
        const Nanos high = lines_.now_ns();
        lines_.set_clocks(mask, true);
        const std::uint8_t bits = p < 24 ? lines_.read_data() : 0;
        lines_.set_clocks(mask, false);
        if (lines_.now_ns() - high > options_.max_high_ns) s.timing_violation = true;
        if (p < 24) {
            for (int c = 0; c < kChips; ++c) {
                if (mask & (1u << c))
                    (*words)[static_cast<std::size_t>(c)] =
                        ((*words)[static_cast<std::size_t>(c)] << 1) | ((bits >> c) & 1u);
            }
        }
    }
}

Hx711Sample Hx711Driver::read_parallel() {
    Hx711Sample s;
    const std::uint64_t ops0 = lines_.ops();
    if (wait_ready(0xFF, s)) {
        s.started_ns = lines_.now_ns();
        std::array<std::uint32_t, kChips> words{};
        pulses(0xFF, &words, s);
        s.stuck = static_cast<std::uint8_t>(~lines_.read_data());  // the 25th pulse pulls DOUT high
        s.finished_ns = lines_.now_ns();
        for (int c = 0; c < kChips; ++c)
            s.counts[static_cast<std::size_t>(c)] = sign_extend_24(words[static_cast<std::size_t>(c)]);
    }
    s.ops = lines_.ops() - ops0;
    return s;
}

Hx711Sample Hx711Driver::read_one_by_one() {
    Hx711Sample s;
    const std::uint64_t ops0 = lines_.ops();
    s.started_ns = lines_.now_ns();
    std::array<std::uint32_t, kChips> words{};
    for (int c = 0; c < kChips; ++c) {
        const auto mask = static_cast<std::uint8_t>(1u << c);
        if (wait_ready(mask, s)) {
            pulses(mask, &words, s);
            s.stuck |= static_cast<std::uint8_t>(~lines_.read_data() & mask);
        }
    }
    s.finished_ns = lines_.now_ns();
    for (int c = 0; c < kChips; ++c)
        s.counts[static_cast<std::size_t>(c)] = sign_extend_24(words[static_cast<std::size_t>(c)]);
    s.ops = lines_.ops() - ops0;
    return s;
}

}  // namespace dw::stand
