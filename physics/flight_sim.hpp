#pragma once
// A simulated flight: vehicles fly the grid legs in formation above the stand (or above a flying
// sufferer); the physics gives the true wrench; the stand samples it through 8 skewed HX711
// clocks, tares and calibrates; the mocap samples the poses; the effects act where they would in
// a real lab (the recording chain). The result is a
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

// A flying sufferer instead of one on the stand: it sways about the stand's point along N and D
// (so its own drag and its height above the floor change), and its wrench is recorded as a flying
// lab records it (wrench_source residual: forces only, each axis with the stand's per-cell noise,
// at rate_hz; no stand, no tare). Its own forces are the recording chain's stage sufferer.
struct FlyingSufferer {
    bool enabled = false;
    double sway_n_m = 0.5, period_n_s = 4.0;  // up to 0.8 m/s, as another lab's random walks
    double sway_d_m = 0.2, period_d_s = 3.0;
    double rate_hz = 100.0;
};
inline constexpr Range kSwayRange{0.0, 2.0, "m"};
inline constexpr Range kSwayPeriodRange{0.5, 600.0, "s"};
inline constexpr Range kResidualRateRange{1.0, 1000.0, "Hz"};

struct FlyOptions {
    std::string formation = "single";
    FlyingSufferer flying_sufferer;
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
    RecordedWrench truth;         // the true wrench on the sufferer, before the stand
};

// Throws dw::InputError when the configuration makes the physics produce a non-finite wrench or
// a vehicle diverge (no NaN, zeros or runaway values are written), dw::Stopped on options.stop.
SimResult simulate_flight(const PhysicsConfig& physics, const FlyOptions& options);

}  // namespace dw::physics
