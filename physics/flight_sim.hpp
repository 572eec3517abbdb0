#pragma once
// A simulated flight: vehicles fly the grid legs in formation above the stand; the physics gives
// the true wrench; the stand samples it through 8 skewed HX711 clocks, tares and calibrates; the
// mocap samples the poses; the effects act where they would in a real lab. The result is a
// flight folder (downwash-flight/1) plus, for tests, the true wrench behind it.
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

#include "flight/flight.hpp"
#include "physics/config.hpp"
#include "physics/trajectory.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics {

struct FlyOptions {
    std::string formation = "single";
    GridOptions grid;
    std::uint64_t seed = 1;
    std::function<void(double)> progress;  // fraction done, 0..1 (may be empty)
    std::stop_token stop;                  // a stop request ends the simulation with dw::Stopped
};

// A simulated vehicle this far from its setpoint has diverged (dynamics too stiff for rate_hz).
inline constexpr double kDivergence_m = 100.0;

struct SimResult {
    flight::Flight flight;
    std::vector<double> truth_t;  // simulation time (= mocap clock) [s]
    std::vector<Wrench> truth;    // the true wrench on the sufferer, before the stand
};

// Throws dw::InputError when the configuration makes the physics produce a non-finite wrench or
// a vehicle diverge (no NaN, zeros or runaway values are written), dw::Stopped on options.stop.
SimResult simulate_flight(const PhysicsConfig& physics, const FlyOptions& options);

}  // namespace dw::physics
