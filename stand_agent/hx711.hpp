#pragma once
// The HX711 driver: waits until all eight chips are ready, then clocks them together and reads
// the eight DOUT lines in one bulk read per bit. A clock-high phase past the chip's 50 µs limit
// (a pre-empted thread) may have powered chips down mid-word: that sample is discarded.
#include <array>
#include <cstdint>
#include <utility>

#include "stand_agent/lines.hpp"

namespace dw::stand {

enum class Gain { a128 = 25, b32 = 26, a64 = 27 };  // value = clock pulses per read
// Each gain with its name (channel and gain, as the datasheet says them).
inline constexpr std::array<std::pair<const char*, Gain>, 3> kGains{
    {{"a128", Gain::a128}, {"a64", Gain::a64}, {"b32", Gain::b32}}};

struct Hx711Sample {
    std::array<std::int32_t, kChips> counts{};  // sign-extended 24-bit values
    std::uint8_t not_ready = 0;                 // chips not ready before the timeout
    std::uint8_t stuck = 0;                     // DOUT still low after the 25th pulse: stuck line
    bool timing_violation = false;              // a clock-high phase exceeded 50 µs
    Nanos started_ns = 0, finished_ns = 0;      // monotonic, around the bit-banging
    std::uint64_t ops = 0;                      // line operations this read took
    bool ok() const { return not_ready == 0 && stuck == 0 && !timing_violation; }
};

struct DriverOptions {
    Gain gain = Gain::a128;
    Nanos ready_timeout_ns = 50'000'000;  // ~4 conversion periods
    Nanos poll_ns = 200'000;              // between ready polls
    Nanos max_high_ns = 50'000;           // T3 max in the datasheet
};

std::int32_t sign_extend_24(std::uint32_t word);

class Hx711Driver {
public:
    Hx711Driver(Hx711Lines& lines, const DriverOptions& options) : lines_(lines), options_(options) {}
    // All chips at once on the shared clock (≤ 80 line operations: a ready poll, 24 x (high,
    // read, low), the gain pulses, and one read that checks every DOUT went high again).
    Hx711Sample read_parallel();
    // One chip after the other on its own clock line: the baseline the parallel read is
    // measured against (needs a bank with separate clocks).
    Hx711Sample read_one_by_one();

private:
    bool wait_ready(std::uint8_t mask, Hx711Sample& s);
    void pulses(std::uint8_t mask, std::array<std::uint32_t, kChips>* words, Hx711Sample& s);

    Hx711Lines& lines_;
    DriverOptions options_;
};

}  // namespace dw::stand
