#include "stand_agent/gpiod_lines.hpp"

#include <gpiod.h>

#include <cerrno>
#include <cstring>
#include <thread>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::stand {

GpiodLines::GpiodLines(const GpioPins& pins) {
    chip_ = gpiod_chip_open_lookup(pins.chip.c_str());
    if (chip_ == nullptr) throw RuntimeError(log::cat("cannot open GPIO chip ", pins.chip, ": ", std::strerror(errno)));
    clock_ = gpiod_chip_get_line(chip_, pins.clock);
    if (clock_ == nullptr || gpiod_line_request_output(clock_, "dw-stand-agent", 0) != 0) {
        const std::string why = std::strerror(errno);
        gpiod_chip_close(chip_);
        throw RuntimeError(log::cat("cannot drive the clock line ", pins.clock, " of ", pins.chip, ": ", why));
    }
    auto* bulk = new gpiod_line_bulk;
    gpiod_line_bulk_init(bulk);
    if (gpiod_chip_get_lines(chip_, const_cast<unsigned*>(pins.data.data()), kChips, bulk) != 0 ||
        gpiod_line_request_bulk_input(bulk, "dw-stand-agent") != 0) {
        const std::string why = std::strerror(errno);
        delete bulk;
        gpiod_line_release(clock_);
        gpiod_chip_close(chip_);
        throw RuntimeError(log::cat("cannot read the 8 DOUT lines of ", pins.chip, ": ", why));
    }
    data_bulk_ = bulk;
}

GpiodLines::~GpiodLines() {
    auto* bulk = static_cast<gpiod_line_bulk*>(data_bulk_);
    gpiod_line_release_bulk(bulk);
    delete bulk;
    gpiod_line_release(clock_);
    gpiod_chip_close(chip_);
}

Nanos GpiodLines::now_ns() { return SystemClock::instance().monotonic_ns(); }

void GpiodLines::sleep_for_ns(Nanos ns) { std::this_thread::sleep_for(std::chrono::nanoseconds(ns)); }

void GpiodLines::do_set_clocks(std::uint8_t, bool high) { gpiod_line_set_value(clock_, high ? 1 : 0); }

std::uint8_t GpiodLines::do_read_data() {
    int values[kChips] = {};
    if (gpiod_line_get_value_bulk(static_cast<gpiod_line_bulk*>(data_bulk_), values) != 0) {
        throw RuntimeError(log::cat("reading the DOUT lines failed: ", std::strerror(errno)));
    }
    std::uint8_t bits = 0;
    for (int i = 0; i < kChips; ++i) bits |= static_cast<std::uint8_t>((values[i] ? 1 : 0) << i);
    return bits;
}

}  // namespace dw::stand
