// sensor_lag: the sensor's first-order response (stage: sensor).
#include <cmath>

#include "physics/effects/common.hpp"
#include "physics/recording_chain.hpp"

namespace dw::physics::effects {
namespace {

struct SensorLagSettings {
    bool enabled = false;
    double tau_s = 0.0;
};

class SensorLag final : public OneNumber<SensorLagSettings> {
public:
    SensorLag() : OneNumber("sensor_lag", &SensorLagSettings::tau_s) {}
    int vocabulary_place() const override { return 2; }  // ../shared/FLIGHT_FORMAT.md
    const EffectFamily* family() const override { return &kDelayFamily; }
    std::optional<std::vector<double>> from_family_quantity(double shift_s) const override {
        if (shift_s <= 0) return std::nullopt;  // a lag cannot make the force early
        return std::vector<double>{shift_s};    // a first-order lag delays a slow signal by its time constant
    }
    std::vector<EffectParameter> parameters() const override {
        return {{"tau_s", "s", 0, 10, 0.0, 0.5, range(0.0, 0.3, 13), 0.0}};
    }
    Stage stage() const override { return Stage::sensor; }
    void sensor_step(const Effects& e, double dt, const Wrench6& x0, const Wrench6& x1, Wrench6& y) const override {
        first_order_lag_step(of(e).tau_s, dt, x0, x1, y);
    }
    std::optional<ProofCase> proof_case() const override {
        return ProofCase{"single", "stand lag, tau 0.08 s", {0.08}, {}, 13};
    }
    std::optional<CoverageCase> coverage_case() const override { return CoverageCase{"single", {{0.02, 0.15}}}; }
    // The shared flights show a lag from about this size: a smaller one is taken for a longer delay on
    // the random walk (docs/REAL.md, the limits).
    std::optional<RealConcealment> real_concealment() const override {
        return RealConcealment{"--lag",
                               "first-order lag time constant [s]",
                               {0.001, 2, "s"},
                               0.151,
                               0.043,
                               false,
                               {},
                               "first-order lag, tau ",
                               " s"};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat(
            "**sensor_lag** — ", who.sensor, " is a first-order low-pass of the force with a time constant of ",
            fixed(v[0], 3), " s: peaks are late and flattened. ",
            who.flying ? "The estimate's own dynamics (the thrust model's motor lag, the state estimator's filtering)"
                       : "The stand's dynamics (filtering, mounting)",
            " were left out. ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_sensor_lag() { return std::make_unique<SensorLag>(); }

}  // namespace dw::physics::effects
