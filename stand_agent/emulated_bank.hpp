#pragma once
// An emulated bank of eight HX711 chips behind the same line interface as the real ones:
// DOUT low when a conversion is ready; 24-bit two's complement, MSB first, one bit per rising
// clock edge; the 25th edge pulls DOUT high; 25/26/27 edges choose channel A/128, B/32, A/64 for
// the next conversion; a clock held high for more than 60 µs powers the chip down, and the
// falling edge resets it (channel A, gain 128, data again after settling); each chip on its own
// oscillator near 80 Hz. Faults can be injected: an unplugged or stuck line, a stretched clock
// pulse, saturation spikes, noise.
#include <array>
#include <functional>

#include "physics/vehicle.hpp"
#include "stand_agent/lines.hpp"

namespace dw::stand {

struct BankOptions {
    double rate_hz = 80.0;
    double rate_skew = 0.01;             // each chip's rate within ±1 %
    double counts_per_newton = 21400.0;  // at gain 128
    double offset_sigma_counts = 50000.0;
    double noise_counts = 0.0;  // 1 sigma, per conversion
    bool shared_clock = true;   // false: one clock line per chip (read one by one)
    Nanos op_cost_ns = 1000;    // virtual time per line operation (manual clock only)
    std::uint64_t seed = 1;
};

class EmulatedBank final : public Hx711Lines {
public:
    // `force(chip, t)`: the force on that chip's load cell at monotonic time t [N].
    using Source = std::function<double(int chip, Nanos t)>;
    // With a ManualClock, time moves only through line operations and sleeps (deterministic
    // tests); with the system clock, in real time (simulation).
    EmulatedBank(Clock& clock, const BankOptions& options, Source force);

    Nanos now_ns() override;
    void sleep_for_ns(Nanos ns) override;
    bool shared_clock() const override { return options_.shared_clock; }

    // Faults.
    void unplug(int chip, bool unplugged = true);  // DOUT floats high: never ready
    void stick_low(int chip, bool stuck = true);   // DOUT stuck low
    void stretch_next_pulse(Nanos extra_high_ns);  // the next clock-high lasts this much longer
    // The thread is pre-empted right after it raises the clock, before it can read the time.
    void stall_after_next_raise(Nanos stall_ns) { stall_after_raise_ns_ = stall_ns; }
    void spike_next(int chip, bool high);  // next conversion reads 0x7FFFFF / 0x800000
    void set_noise(double counts_sigma) { options_.noise_counts = counts_sigma; }

    int gain(int chip) const { return chips_[static_cast<std::size_t>(chip)].gain; }
    bool powered_down(int chip) const { return chips_[static_cast<std::size_t>(chip)].down; }
    double offset(int chip) const { return chips_[static_cast<std::size_t>(chip)].offset; }
    std::uint64_t conversions(int chip) const { return chips_[static_cast<std::size_t>(chip)].conversions; }

protected:
    void do_set_clocks(std::uint8_t mask, bool high) override;
    std::uint8_t do_read_data() override;

private:
    struct Chip {
        double period_ns = 0;
        Nanos next_ns = 0;  // next conversion completes
        double offset = 0;
        int gain = 128;
        bool channel_b = false;
        bool ready = false;
        std::uint32_t word = 0;      // the converted value, 24 bits
        std::uint32_t shifting = 0;  // the word being shifted out
        int pulses = 0;
        bool clock_high = false;
        Nanos high_since = 0;
        bool down = false;
        bool unplugged = false, stuck_low = false;
        int spike = 0;
        std::uint64_t conversions = 0;
    };
    void advance(Nanos now);
    void tick_op();
    std::int32_t convert(int chip, Nanos t);

    Clock& clock_;
    ManualClock* manual_;
    BankOptions options_;
    Source force_;
    physics::Rng rng_;
    std::array<Chip, kChips> chips_;
    Nanos stretch_ns_ = 0;
    Nanos stall_after_raise_ns_ = 0;
};

}  // namespace dw::stand
