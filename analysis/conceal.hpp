#pragma once
// Effects concealed in a recorded flight: the real-data proofs' way to know the truth on data
// whose physics nobody knows. An effect of the rig's measurement chain is put into the recording
// through the recording chain itself (physics/recording_chain.hpp); what the explainer should then
// fit on top of the flight's own fit is the concealed value combined with what the untouched
// flight already shows of that effect.
#include <cstddef>
#include <functional>
#include <map>
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

// How much of each concealable effect a proof hides: effect name -> size. Each effect of the rig
// declares its concealment (physics::RealConcealment): its option, its sizes, how it combines.
using Concealed = std::map<std::string, double>;
enum class ConcealedSize { single, session };
// Every concealable effect at its size for one flight's proof or for a session's.
Concealed concealed_sizes(ConcealedSize which);

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

// The concealments of m's effects at m's sizes, in the vocabulary's order.
std::vector<Concealment> concealments(const Concealed& m);
// The concealable effects' names, comma-separated (for messages).
std::string concealment_names();
// Whether an effect's axes are those it is concealed between (an effect without axes: always).
bool on_concealed_axes(const physics::EffectType& t, physics::AxisPair axes);

}  // namespace dw::analysis
