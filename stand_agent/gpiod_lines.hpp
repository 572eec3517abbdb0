#pragma once
// Hx711Lines on libgpiod 1.6 (Debian's and Raspberry Pi OS bookworm's): one bulk request for the
// eight DOUT lines (inputs), one for the clock line (output, shared by all chips).
#include <array>
#include <string>

#include "core/numbers.hpp"
#include "stand_agent/lines.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace dw::stand {

inline constexpr Range kLineOffsetRange{0, 1023};  // a GPIO line offset on the chip

struct GpioPins {
    std::string chip = "gpiochip0";
    unsigned clock = 0;
    std::array<unsigned, kChips> data{};
};

class GpiodLines final : public Hx711Lines {
public:
    // Throws dw::RuntimeError naming the chip or line when the request fails (no GPIO here).
    explicit GpiodLines(const GpioPins& pins);
    ~GpiodLines() override;
    Nanos now_ns() override;
    void sleep_for_ns(Nanos ns) override;
    bool shared_clock() const override { return true; }

protected:
    void do_set_clocks(std::uint8_t mask, bool high) override;
    std::uint8_t do_read_data() override;

private:
    gpiod_chip* chip_ = nullptr;
    gpiod_line* clock_ = nullptr;
    void* data_bulk_ = nullptr;  // struct gpiod_line_bulk, kept opaque here
};

}  // namespace dw::stand
