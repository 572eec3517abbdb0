#pragma once
// The recording chain: what the lab's instruments make of the truth — positions → air → forces on
// the sufferer → sensor → sampling on the recording's clock → tare → calibration → recording.
// RecordingChain::record runs the stages in that order for every caller: the simulator
// (physics/flight_sim.cpp, with the stand's chips), the explainer's resimulation
// (analysis/resimulation.cpp, with a sampler that matches the chips at the recorded stamps) and a
// concealment (analysis/conceal.cpp, on a recording's own samples); dw-stand-agent --sim runs its
// live form (RecordingChain::Live). So each effect has one discretisation: each stage calls the
// effects that act there (EffectType::stage), in registry order, while they are on. The air is
// evaluated where it is (wrench_model); the chain carries a flying sufferer's own forces and
// everything the recording adds. The samplers are in physics/samplers.hpp.
#include <array>
#include <functional>
#include <vector>

#include "physics/config.hpp"
#include "physics/effect_types.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics {

// A recording's samples: their stamps (s, on the recording's clock) and wrenches (NED, SI).
struct Samples {
    std::vector<double> stamps;
    RecordedWrench w;
};

// How the sensor's output becomes the recording's samples (physics/samplers.hpp).
class Sampler {
public:
    virtual ~Sampler() = default;
    // The felt series on the grid t (s, the poses' clock), sampled and stamped on the recording's
    // clock, which runs clock_delay_s late.
    virtual Samples sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) = 0;
    // The tare stage: the samples zeroed by their mean over their first tare_s (none given 0). An
    // instrument that zeroes otherwise says how (the stand's chips: their counts, as its agent does).
    virtual void tare(Samples& s, double tare_s) const;
};

// What RecordingChain::record is given.
struct ChainInput {
    std::vector<double> t;                               // the grid (s, the poses' clock)
    RecordedWrench force;                                // the air's wrench on the sufferer at each t
    std::function<SuffererState(std::size_t)> sufferer;  // a flying sufferer's state at t[i] (empty: none)
    double tare_s = 0;  // the samples zeroed by their mean over the first tare_s (0: kept as they are)
    const RecordedWrench* recorded = nullptr;  // the recording's own samples, for the calibration (null: each its own)
    bool moments_measured = true;              // false: the moments recorded as zero (a residual source)
    std::function<void(const RecordedWrench&)> felt;  // if given: shown the force on the sufferer, its own added
};

class RecordingChain {
public:
    explicit RecordingChain(const Effects& effects);

    // The whole chain after the air, in its stage order: the sufferer's own forces, the sensor, the
    // sampler (on the recording's clock), the tare, the calibration, the recording.
    Samples record(ChainInput in, Sampler& sampler) const;

    // The chain live, for a simulated stand (dw-stand-agent --sim): each call gives the calibrated
    // reading at time t (s) of the force x then; the stand's chips sample it, the agent tares it
    // and the machine's clock stamps it.
    class Live;

    // Each stage alone (record runs them; tests look at one).
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

class RecordingChain::Live {
public:
    explicit Live(const RecordingChain& chain) : chain_(chain), sensor_(chain) {}
    Wrench6 read(double t, const Wrench6& x);

private:
    const RecordingChain& chain_;
    SensorStream sensor_;
};

// How many of the samples at times t fall in the first tare_s: those a tare averages.
std::size_t tare_count(const std::vector<double>& t, double tare_s);

// The sufferer as the stage-sufferer effects see it: its vehicle v in configuration c, at p moving
// at velocity (NED, SI).
SuffererState sufferer_state(const PhysicsConfig& c, const VehicleParams& v, const Vec3& p, const Vec3& velocity);

// One step of a first-order lag of time constant tau_s (s) over dt seconds, the input going linearly
// from x0 to x1 (exact for that input); y, the output at the step's start, becomes its end's.
void first_order_lag_step(double tau_s, double dt, const Wrench6& x0, const Wrench6& x1, Wrench6& y);

}  // namespace dw::physics
