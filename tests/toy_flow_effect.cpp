// Issue 73: a flow effect defined in one file — this one, its last line its registration. It acts
// where the air is evaluated (stage air: physics/wrench_model.hpp calls its hook for every sample
// the simulator, the replay and the explainer's fits evaluate). Linked into a test, and built as
// an effect module that the shipped dw-sim loads (DW_EFFECT_MODULES; tests/CMakeLists.txt).
// The jets' outwash: each jet above the sufferer pushes it sideways, away from its axis, by a
// fraction of its thrust that fades over a jet's width — physics the lab's jets do not have.
#include <cmath>

#include "core/log.hpp"
#include "core/numbers.hpp"
#include "physics/effect_types.hpp"
#include "physics/wrench_model.hpp"

namespace {

using namespace dw::physics;

constexpr double kOutwashWidth_m = 0.3;  // the distance over which it fades (1/e at this offset)

class ToyOutwash final : public EffectType {
public:
    std::string name() const override { return "toy_outwash"; }
    std::vector<EffectParameter> parameters() const override { return {{"fraction", "", -1, 1, -0.5, 0.5, {}, 0.0}}; }
    bool changes_flow() const override { return true; }
    Wrench6 air_wrench(const Effects& e, const AirScene& s) const override {
        const double fraction = values(e).front();
        Wrench6 w{};
        for (const auto& p : s.producers) {
            if (p.position.z() >= s.sufferer.z()) continue;  // not above the sufferer
            const double dx = (s.sufferer.x() - p.position.x()) / kOutwashWidth_m,
                         dy = (s.sufferer.y() - p.position.y()) / kOutwashWidth_m;
            const double push = fraction * p.jet.thrust_n * std::exp(-(dx * dx + dy * dy));
            w[0] += push * dx;
            w[1] += push * dy;
        }
        return w;
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return dw::log::cat("**toy_outwash** — each jet above pushes the sufferer away from its axis by ",
                            dw::fixed(v[0], 3), " of its thrust (fading over ", kOutwashWidth_m, " m). ");
    }
};
const EffectRegistration<ToyOutwash> registered;

}  // namespace
