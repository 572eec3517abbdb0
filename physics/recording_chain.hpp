#pragma once
// The recording chain: what the lab's instruments make of the truth — positions → air → forces on
// the sufferer → sensor → tare → calibration → clock → recording. The simulator
// (physics/flight_sim.cpp), the explainer's resimulation (analysis/resimulation.cpp) and
// dw-stand-agent --sim all pass their wrench through it, so each effect has one discretisation:
// each stage calls the effects that act there (EffectType::stage), in registry order, while they
// are on. The air and a flying sufferer's own forces are evaluated where they are (wrench_model,
// the resimulation); the chain carries everything the recording adds to them.
#include <array>
#include <vector>

#include "physics/config.hpp"
#include "physics/effect_types.hpp"

namespace dw::physics {

class RecordingChain {
public:
    explicit RecordingChain(const Effects& effects);

    // positions: the motion capture's error, added to every true position it reports (NED, m).
    std::array<double, 3> position_error_m() const;
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
    // recording: the effects kept in Effects::extra, on the recorded wrench at its stamps.
    void recording(const std::vector<double>& stamps, RecordedWrench& w) const;

private:
    const Effects& effects_;
    std::array<std::vector<const EffectType*>, 7> at_;  // the effects on, by Stage
    const std::vector<const EffectType*>& at(Stage s) const { return at_[static_cast<std::size_t>(s)]; }
};

// One step of a first-order lag of time constant tau_s (s) over dt seconds, the input going linearly
// from x0 to x1 (exact for that input); y, the output at the step's start, becomes its end's.
void first_order_lag_step(double tau_s, double dt, const Wrench6& x0, const Wrench6& x1, Wrench6& y);

}  // namespace dw::physics
