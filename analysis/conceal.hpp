#pragma once
// Effects concealed in a recorded flight: the real-data proofs' way to know the truth on data
// whose physics nobody knows. An effect of the rig's measurement chain is put into the recording
// through the recording chain itself (physics/recording_chain.hpp); what the explainer should then
// fit on top of the flight's own fit is the concealed value combined with what the untouched
// flight already shows of that effect.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "flight/flight.hpp"
#include "physics/config.hpp"

namespace dw::analysis {

// A parameter's true value in a proof.
struct Truth {
    std::string effect, param;
    double value;
    std::size_t index = 0;  // into the effect's parameters
};

// How much of each effect the real-data proof conceals (values not round; `dw-explain real-proof`
// --clock, --scale, --lag, --leak probe what a flight can show). The scale and the lag are where
// the shared flights can show them: a smaller lag is taken for a longer delay on the random walk,
// a smaller scale for the flight's own separation-dependent misfit (docs/REAL.md, the limits).
struct Concealed {
    double clock_s = 0.083;  // the wrench stamped this late
    double scale = 1.61;     // the wrench multiplied by this
    double lag_s = 0.151;    // the wrench seen through a first-order lag of this time constant
    double leak = 0.113;     // f_n += leak × f_d
};

// The axes the cross-talk is concealed between: f_d leaks into f_n.
inline constexpr physics::AxisPair kConcealedLeakAxes{2, 0};

// An effect concealed in a recording, and what the explainer should then fit on top of the
// flight's own fit: the concealed value combined with what the untouched flight already shows of
// that effect (its fit on top of its own fit, accepted or not; else the own fit's setting).
struct Concealment {
    std::string name, description;
    std::function<void(flight::Flight&)> conceal;
    std::function<Truth(const physics::Effects& own, std::optional<double> untouched)> expect;
};

// The recording-side effects of fx put into a recorded flight through the recording chain: the
// sensor on the recorded stamps, the calibration, the clock (the recording keeps its own tare: the
// calibration is linear, so its zero moves with it).
void conceal(flight::Flight& f, const physics::Effects& fx);

// The four concealments (clock_offset, force_scale, sensor_lag, cell_crosstalk) at m's sizes.
std::vector<Concealment> concealments(const Concealed& m);
// Their names, comma-separated (for messages).
inline constexpr const char* kConcealmentNames = "clock_offset, force_scale, sensor_lag or cell_crosstalk";

}  // namespace dw::analysis
