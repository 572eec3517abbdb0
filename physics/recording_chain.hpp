#pragma once
// The recording chain: what the lab's instruments make of the truth — positions → air → forces on
// the sufferer → sensor → tare → calibration → clock → recording. The simulator
// (physics/flight_sim.cpp), the explainer's resimulation (analysis/resimulation.cpp) and
// dw-stand-agent --sim all pass their wrench through it, so each effect has one discretisation:
// each stage calls the effects that act there (EffectType::stage), in registry order, while they
// are on. The air is evaluated where it is (wrench_model); the chain carries a flying sufferer's
// own forces and everything the recording adds.
#include <array>
#include <vector>

#include "physics/config.hpp"
#include "physics/effect_types.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics {

class RecordingChain {
public:
    explicit RecordingChain(const Effects& effects);

    // positions: the motion capture's error, added to every true position it reports (NED, m).
    Vec3 position_error_m() const;
    // sufferer: the force a flying sufferer's own motion adds (body drag, ground effect); whether
    // any effect acts there.
    Wrench6 sufferer_force(const SuffererState& s) const;
    bool acts_on_sufferer() const { return !at(Stage::sufferer).empty(); }
    // sensor: the force on the sufferer, sampled at times t, becomes what the sensor reads.
    void sensor(const std::vector<double>& t, RecordedWrench& series) const;
    // The same, live: each call gives the reading at time t (s) of the force x then; a time not
    // after the last one gives the last reading.
    class SensorStream {
    public:
        explicit SensorStream(const RecordingChain& chain) : chain_(chain) {}
        Wrench6 read(double t, const Wrench6& x);

    private:
        const RecordingChain& chain_;
        std::vector<Wrench6> in_, out_;  // per sensor effect: its last input and reading
        double t_ = 0;
    };
    // calibration: one calibrated, tared sample; `recorded` as EffectType::on_calibration says.
    void calibration(Wrench6& w, const Wrench6& recorded) const;
    void calibration(Wrench6& w) const;  // while simulating: the sample is its own recording
    // clock: how late the wrench's stamps run against the poses' (s).
    double clock_delay_s() const;
    // recording: the effects acting on the recorded wrench as written (those kept in
    // Effects::extra by default), at its stamps.
    void recording(const std::vector<double>& stamps, RecordedWrench& w) const;

private:
    const Effects& effects_;
    std::array<std::vector<const EffectType*>, kStages> at_;  // the effects on, by Stage
    const std::vector<const EffectType*>& at(Stage s) const { return at_[static_cast<std::size_t>(s)]; }
};

// The sufferer as the stage-sufferer effects see it: its vehicle v in configuration c, at p moving
// at velocity (NED, SI).
SuffererState sufferer_state(const PhysicsConfig& c, const VehicleParams& v, const Vec3& p, const Vec3& velocity);

// One step of a first-order lag of time constant tau_s (s) over dt seconds, the input going linearly
// from x0 to x1 (exact for that input); y, the output at the step's start, becomes its end's.
void first_order_lag_step(double tau_s, double dt, const Wrench6& x0, const Wrench6& x1, Wrench6& y);

}  // namespace dw::physics
