#pragma once
// The narrow line interface the HX711 driver talks to: one request for the clock line(s), one
// for the eight DOUT lines, each read in bulk. Two implementations: libgpiod (the Pi) and an
// emulated HX711 bank (tests, simulation). Every line operation is counted.
#include <cstdint>

#include "core/clock.hpp"

namespace dw::stand {

inline constexpr int kChips = 8;

class Hx711Lines {
public:
    virtual ~Hx711Lines() = default;
    // Drives the clock line(s) of the chips in `mask` (bit i = chip i); a shared clock ignores it.
    void set_clocks(std::uint8_t mask, bool high) {
        ++ops_;
        do_set_clocks(mask, high);
    }
    // All eight DOUT lines in one read: bit i = DOUT of chip i (1 = high = not ready / a 1 bit).
    std::uint8_t read_data() {
        ++ops_;
        return do_read_data();
    }
    virtual Nanos now_ns() = 0;               // monotonic, for the 50 µs guard
    virtual void sleep_for_ns(Nanos ns) = 0;  // between ready polls
    virtual bool shared_clock() const = 0;
    std::uint64_t ops() const { return ops_; }

protected:
    virtual void do_set_clocks(std::uint8_t mask, bool high) = 0;
    virtual std::uint8_t do_read_data() = 0;

private:
    std::uint64_t ops_ = 0;
};

}  // namespace dw::stand
