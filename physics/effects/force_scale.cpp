// force_scale: a gain on the whole recorded wrench (stage: calibration).
#include <cmath>

#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

struct ForceScaleSettings {
    bool enabled = false;
    double scale = 1.0;
};

class ForceScale final : public OneNumber<ForceScaleSettings> {
public:
    ForceScale() : OneNumber("force_scale", &ForceScaleSettings::scale) {}
    int vocabulary_place() const override { return 5; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override { return {{"scale", "", 0, 10, 0.3, 3.0, {}, 1.0}}; }
    Stage stage() const override { return Stage::calibration; }
    const EffectFamily* family() const override { return &kPushFamily; }
    bool gain_of_the_push() const override { return true; }
    void on_calibration(const Effects& e, Wrench6& w, const Wrench6&) const override {
        for (auto& v : w) v *= of(e).scale;
    }
    std::optional<CoverageCase> coverage_case() const override { return CoverageCase{"single", {{0.8, 1.25}}}; }
    std::optional<std::vector<double>> in_two_effects_case() const override { return std::vector<double>{1.15}; }
    // The shared flights show a scale from about this size: a smaller one is taken for a flight's own
    // separation-dependent misfit (docs/REAL.md, the limits).
    std::optional<RealConcealment> real_concealment() const override {
        return RealConcealment{"--scale", "the wrench multiplied by this", {0.1, 10}, 1.61, 1.31, true, {}, "wrench × ",
                               ""};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat("**force_scale** — the recorded wrench is ", fixed(v[0], 3),
                        " × the simulated one everywhere: a mass, drag coefficient or ",
                        who.flying ? "thrust-model gain" : "load-cell gain", " that differs from the model by ",
                        fixed((v[0] - 1) * 100, 1), " %. ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_force_scale() { return std::make_unique<ForceScale>(); }

}  // namespace dw::physics::effects
