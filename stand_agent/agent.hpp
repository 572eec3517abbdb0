#pragma once
// The stand agent's logic, apart from DDS and hardware so tests drive it with a manual clock:
// spike and saturation rejection (a per-cell Hampel filter), faults (a cell not ready names it;
// a timing violation discards the sample), the tare at hover thrust, the calibrated wrench and
// the status.
#include <array>
#include <deque>
#include <optional>
#include <string>

#include "core/clock.hpp"
#include "dw/msg/Stand.h"
#include "dw/msg/Wrench.h"
#include "stand_agent/calibration.hpp"
#include "stand_agent/hx711.hpp"

namespace dw::stand {

struct AgentOptions {
    Calibration calibration;
    int tare_samples = 80;  // 1 s at 80 Hz
    int hampel_window = 7;
    double hampel_k = 3.0;
    double spike_min_n = 5.0;  // never call a change below this a spike [N]
};

class StandAgent {
public:
    StandAgent(const AgentOptions& options, Clock& clock);

    struct Output {
        bool publish = false;  // frame and wrench are valid
        msg::LoadCellFrame frame;
        msg::WrenchStamped wrench;
        bool status_changed = false;
    };
    Output process(const Hx711Sample& sample);
    void request_tare();  // CALIBRATE: the next tare_samples become the zero
    msg::StandStatus status() const;
    bool tared() const { return tared_; }
    const CellVector& zero() const { return zero_; }

private:
    std::int32_t filter(int cell, std::int32_t raw, msg::CellStatus& status);
    void set_state(msg::StandState s, std::string message, std::vector<std::uint32_t> faults = {});

    AgentOptions options_;
    Clock& clock_;
    std::array<std::deque<std::int32_t>, kChips> history_;
    CellVector zero_ = CellVector::Zero();
    bool tared_ = false;
    int taring_left_ = 0;
    CellVector tare_sum_ = CellVector::Zero();
    Nanos last_tare_ns_ = 0;
    msg::StandState state_ = msg::STAND_STARTING;
    std::string message_ = "starting";
    std::vector<std::uint32_t> fault_cells_;
    std::uint64_t published_ = 0, discarded_ = 0, spikes_ = 0;
    std::deque<Nanos> recent_;  // publish times over the last second, for the rate
};

}  // namespace dw::stand
