// Issue 17: an effect defined in one file — this one, its last line its registration. Linked into a
// test, and built as an effect module that the shipped dw-sim and dw-explain load
// (DW_EFFECT_MODULES, physics/effect_types.hpp; tests/CMakeLists.txt), it is read from a
// configuration, simulated, fitted by the explainer and written in its report without any other
// file naming it.
// A steady sideways force the physics knows nothing of (a draught across the stand, say).
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "physics/effect_types.hpp"

namespace {

using namespace dw::physics;

class ToyLateralBias final : public EffectType {
public:
    std::string name() const override { return "toy_lateral_bias"; }
    std::vector<EffectParameter> parameters() const override { return {{"bias_n", "N", -1, 1, -0.5, 0.5, {}, 0.0}}; }
    void on_recording(const std::vector<double>& v, const std::vector<double>&, RecordedWrench& w) const override {
        for (auto& s : w) s[1] += v[0];
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return dw::log::cat("**toy_lateral_bias** — ", who.sensor, " reads a steady ", dw::fixed(v[0], 3),
                            " N on f_e that the physics does not make. ");
    }
};
const EffectRegistration<ToyLateralBias> registered;

}  // namespace
