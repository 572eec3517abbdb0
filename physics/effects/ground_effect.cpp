// ground_effect: a flying sufferer's extra lift near the floor, by the image-rotor law (stage: sufferer).
#include <cmath>

#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

struct GroundEffectSettings {
    bool enabled = false;
    double coefficient = 0.0;
};

class GroundEffect final : public OneNumber<GroundEffectSettings> {
public:
    GroundEffect() : OneNumber("ground_effect", &GroundEffectSettings::coefficient) {}
    int vocabulary_place() const override { return 10; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", 0, 50, 0.0, 50.0, range(0.0, 20.0, 5), 0.0}};
    }
    bool applies(int, bool flying) const override { return flying; }
    Stage stage() const override { return Stage::sufferer; }
    // Lift (−D) of coefficient × hover thrust × (R / 4h)², h the height above the floor (D = 0),
    // held at the propeller radius: the law's pole is not reached by a flying vehicle.
    Wrench6 sufferer_force(const Effects& e, const SuffererState& s) const override {
        const double h = std::max(-s.position_m[2], s.prop_radius_m);
        return {0, 0, -of(e).coefficient * s.hover_thrust_n * std::pow(s.prop_radius_m / (4 * h), 2), 0, 0, 0};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat("**ground_effect** — extra lift near the floor: ", fixed(v[0], 2),
                        " × the hover thrust × (R / 4h)². ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_ground_effect() { return std::make_unique<GroundEffect>(); }

}  // namespace dw::physics::effects
