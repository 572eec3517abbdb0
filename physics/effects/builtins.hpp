#pragma once
// The vocabulary's built-in effects (../shared/FLIGHT_FORMAT.md), one file each in this folder,
// listed once here in the vocabulary's order: a new built-in is its file, its test and one line
// below. (A lab's own effect needs no line here: an effect module, physics/effect_types.hpp.)
#include <memory>

#include "physics/effect_types.hpp"

#define DW_BUILTIN_EFFECTS(X) \
    X(clock_offset)           \
    X(sensor_lag)             \
    X(wake_transport)         \
    X(position_offset)        \
    X(force_scale)            \
    X(cell_crosstalk)         \
    X(jet_merging)            \
    X(floor_recirculation)    \
    X(body_drag)              \
    X(ground_effect)

namespace dw::physics::effects {

#define DW_DECLARE_EFFECT(name) std::unique_ptr<EffectType> make_##name();
DW_BUILTIN_EFFECTS(DW_DECLARE_EFFECT)
#undef DW_DECLARE_EFFECT

}  // namespace dw::physics::effects
