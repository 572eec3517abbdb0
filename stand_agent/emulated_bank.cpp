#include "stand_agent/emulated_bank.hpp"

#include <cmath>
#include <thread>

namespace dw::stand {

EmulatedBank::EmulatedBank(Clock& clock, const BankOptions& options, Source force)
    : clock_(clock),
      manual_(dynamic_cast<ManualClock*>(&clock)),
      options_(options),
      force_(std::move(force)),
      rng_(options.seed) {
    const Nanos now = clock_.monotonic_ns();
    for (auto& c : chips_) {
        c.period_ns = static_cast<double>(kNanosPerSecond) /
                      (options_.rate_hz * (1.0 + options_.rate_skew * (2 * rng_.uniform() - 1)));
        c.next_ns = now + static_cast<Nanos>(c.period_ns * rng_.uniform());
        c.offset = options_.offset_sigma_counts * rng_.normal();
    }
}

Nanos EmulatedBank::now_ns() { return clock_.monotonic_ns(); }

void EmulatedBank::sleep_for_ns(Nanos ns) {
    if (manual_) manual_->advance(std::chrono::nanoseconds(ns));
    else std::this_thread::sleep_for(std::chrono::nanoseconds(ns));
}

void EmulatedBank::tick_op() {
    if (manual_) manual_->advance(std::chrono::nanoseconds(options_.op_cost_ns));
}

void EmulatedBank::unplug(int chip, bool u) { chips_[static_cast<std::size_t>(chip)].unplugged = u; }
void EmulatedBank::stick_low(int chip, bool s) { chips_[static_cast<std::size_t>(chip)].stuck_low = s; }
void EmulatedBank::stretch_next_pulse(Nanos extra) { stretch_ns_ = extra; }
void EmulatedBank::spike_next(int chip, bool high) { chips_[static_cast<std::size_t>(chip)].spike = high ? 1 : -1; }

std::int32_t EmulatedBank::convert(int i, Nanos t) {
    Chip& c = chips_[static_cast<std::size_t>(i)];
    if (c.spike != 0) {
        const std::int32_t code = c.spike > 0 ? 0x7FFFFF : -0x800000;
        c.spike = 0;
        return code;
    }
    // Channel B is not wired on the stand; channel A scales with the gain.
    const double f = c.channel_b ? 0.0 : force_(i, t);
    double v = c.offset + f * options_.counts_per_newton * (c.gain / 128.0);
    if (options_.noise_counts > 0) v += options_.noise_counts * rng_.normal();
    v = std::round(v);
    if (v > 0x7FFFFF) return 0x7FFFFF;
    if (v < -0x800000) return -0x800000;
    return static_cast<std::int32_t>(v);
}

void EmulatedBank::advance(Nanos now) {
    for (int i = 0; i < kChips; ++i) {
        Chip& c = chips_[static_cast<std::size_t>(i)];
        if (c.clock_high && !c.down && now - c.high_since > 60'000) c.down = true;  // power-down
        if (c.down) continue;
        while (now >= c.next_ns) {
            if (c.pulses >= 1 && c.pulses < 25) {
                // Mid-read: the output register is busy; this conversion is lost, as on the chip.
                c.next_ns += static_cast<Nanos>(c.period_ns);
                continue;
            }
            // The pulse count of the read just finished sets this conversion's channel and gain.
            if (c.pulses == 25) {
                c.gain = 128;
                c.channel_b = false;
            } else if (c.pulses == 26) {
                c.gain = 32;
                c.channel_b = true;
            } else if (c.pulses == 27) {
                c.gain = 64;
                c.channel_b = false;
            }
            c.pulses = 0;
            c.word = static_cast<std::uint32_t>(convert(i, c.next_ns)) & 0xFFFFFF;
            c.ready = true;
            ++c.conversions;
            c.next_ns += static_cast<Nanos>(c.period_ns);
        }
    }
}

void EmulatedBank::do_set_clocks(std::uint8_t mask, bool high) {
    tick_op();
    Nanos now = clock_.monotonic_ns();
    advance(now);
    for (int i = 0; i < kChips; ++i) {
        Chip& c = chips_[static_cast<std::size_t>(i)];
        if (!options_.shared_clock && !(mask & (1u << i))) continue;
        if (high && !c.clock_high) {
            c.clock_high = true;
            c.high_since = now;
            if (c.down) continue;
            if (c.pulses == 0 && !c.ready) continue;  // no conversion waiting: nothing to shift
            if (c.pulses == 0) c.shifting = c.word;   // the first edge latches the data register
            ++c.pulses;
            if (c.pulses == 25) c.ready = false;  // the 25th edge pulls DOUT high
        } else if (!high && c.clock_high) {
            c.clock_high = false;
            if (c.down) {
                // Back low after a power-down: the chip resets to channel A, gain 128 and
                // needs about four conversions (50 ms at 80 SPS) to settle.
                c.down = false;
                c.gain = 128;
                c.channel_b = false;
                c.pulses = 0;
                c.ready = false;
                c.next_ns = now + static_cast<Nanos>(4 * c.period_ns);
            }
        }
    }
    if (high && stall_after_raise_ns_ > 0) {  // pre-empted with the clock just raised
        sleep_for_ns(stall_after_raise_ns_);
        stall_after_raise_ns_ = 0;
    }
}

std::uint8_t EmulatedBank::do_read_data() {
    tick_op();
    if (stretch_ns_ > 0 && chips_[0].clock_high) {
        // A pre-empted thread: the clock stays high much longer than intended.
        sleep_for_ns(stretch_ns_);
        stretch_ns_ = 0;
    }
    advance(clock_.monotonic_ns());
    std::uint8_t bits = 0;
    for (int i = 0; i < kChips; ++i) {
        const Chip& c = chips_[static_cast<std::size_t>(i)];
        bool dout;
        if (c.unplugged || c.down) dout = true;
        else if (c.stuck_low) dout = false;
        else if (c.pulses >= 1 && c.pulses <= 24) dout = (c.shifting >> (24 - c.pulses)) & 1u;  // MSB first
        else dout = !c.ready;
        bits |= static_cast<std::uint8_t>(dout ? 1u << i : 0u);
    }
    return bits;
}

}  // namespace dw::stand
