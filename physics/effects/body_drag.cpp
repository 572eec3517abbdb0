// body_drag: a flying sufferer's own drag against its motion through still air (stage: sufferer).
#include <cmath>

#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

struct BodyDragSettings {
    bool enabled = false;
    double cda_h_m2 = 0.0, cda_v_m2 = 0.0;
};

class BodyDrag final : public BuiltIn<BodyDragSettings> {
public:
    BodyDrag() : BuiltIn("body_drag") {}
    int vocabulary_place() const override { return 9; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override {
        return {{"cda_h_m2", "m²", 0, 10, 0.0, 0.1, {}, 0.0}, {"cda_v_m2", "m²", 0, 10, 0.0, 0.1, {}, 0.0}};
    }
    bool applies(int, bool flying) const override { return flying; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override { of(e) = {on, v[0], v[1]}; }
    std::vector<double> values(const Effects& e) const override { return {of(e).cda_h_m2, of(e).cda_v_m2}; }
    Stage stage() const override { return Stage::sufferer; }
    // f = −½ ρ C_d A |v| v, horizontally and vertically with their own areas.
    Wrench6 sufferer_force(const Effects& e, const SuffererState& s) const override {
        const auto& v = s.velocity_m_s;
        const double half_rho = 0.5 * s.air_density_kg_m3, vh = std::hypot(v[0], v[1]);
        const auto& x = of(e);
        return {-half_rho * x.cda_h_m2 * vh * v[0],
                -half_rho * x.cda_h_m2 * vh * v[1],
                -half_rho * x.cda_v_m2 * std::abs(v[2]) * v[2],
                0,
                0,
                0};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat("**body_drag** — the flying sufferer's own drag against its motion through still air: C_d A = ",
                        fixed(v[0], 4), " m² horizontally, ", fixed(v[1], 4),
                        " m² vertically (f = −½ ρ C_d A |v| v). The simulation had only the neighbours' air. ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_body_drag() { return std::make_unique<BodyDrag>(); }

}  // namespace dw::physics::effects
