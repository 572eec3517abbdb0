// ground_effect: a flying sufferer's extra lift near the floor (stage: sufferer; its physics is the resimulation's).
#include <cmath>

#include "physics/effects/builtins.hpp"
#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

class GroundEffect final : public OneNumber<DW_FIELD(ground_effect)> {
public:
    GroundEffect() : OneNumber(&Effects::ground_effect, &DW_FIELD(ground_effect)::coefficient) {}
    std::string name() const override { return "ground_effect"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", 0, 50, 0.0, 50.0, range(0.0, 20.0, 5), 0.0}};
    }
    bool applies(int, bool flying) const override { return flying; }
    Stage stage() const override { return Stage::sufferer; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat("**ground_effect** — extra lift near the floor: ", f3(v[0], 2),
                        " × the hover thrust × (R / 4h)². ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_ground_effect() { return std::make_unique<GroundEffect>(); }

}  // namespace dw::physics::effects
