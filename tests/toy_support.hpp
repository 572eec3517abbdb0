#pragma once
// What the toy effects' tests (test_effect_registry.cpp, test_flow_effect.cpp) share: a physics
// file that switches one effect on, and the flight both fly, in-process and through dw-sim.
#include <string>
#include <vector>

#include "core/log.hpp"
#include "physics/config.hpp"
#include "physics/flight_sim.hpp"

namespace dw::test {

// "format: ...\neffects:\n  <effect>:\n    enabled: true\n    <key>: <value>\n"
inline std::string one_effect_yaml(const std::string& effect, const std::string& key, double value) {
    return log::cat("format: downwash-physics/1\neffects:\n  ", effect, ":\n    enabled: true\n    ", key, ": ", value,
                    "\n");
}

// The toys' flight: one neighbour, 12 legs, seed 5; and dw-sim fly's options for the same.
inline physics::FlyOptions toy_flight() {
    physics::FlyOptions o;
    o.formation = "single";
    o.grid.legs = 12;
    o.seed = 5;
    return o;
}
inline const std::vector<std::string> kToyFlightArgs{"fly", "--formation", "single", "--legs", "12", "--seed", "5"};
inline flight::Flight fly_toy(const physics::PhysicsConfig& c) { return simulate_flight(c, toy_flight()).flight; }

}  // namespace dw::test
