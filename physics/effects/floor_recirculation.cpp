// floor_recirculation: jets hitting the floor coming back as a bias (stage: air).
#include <cmath>

#include "physics/effects/common.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics::effects {
namespace {

struct FloorRecirculationSettings {
    bool enabled = false;
    double coefficient = 0.02;
    double length_m = 1.0;
};

class FloorRecirculation final : public BuiltIn<FloorRecirculationSettings> {
public:
    FloorRecirculation() : BuiltIn("floor_recirculation") {}
    int vocabulary_place() const override { return 8; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", 0, 1, 0.0, 0.3, range(0.0, 0.1, 5), 0.02}};
    }
    bool changes_flow() const override { return true; }
    // Jets that reach the floor come back up around the stand: an upward bias that grows with each
    // impinging jet and fades with its lateral distance.
    Wrench6 air_wrench(const Effects& fx, const AirScene& s) const override {
        const auto& e = of(fx);
        Wrench6 w{};
        for (const auto& p : s.producers) {
            if (p.position.z() >= s.sufferer.z()) continue;  // not above the sufferer
            const double dx = p.position.x() - s.sufferer.x(), dy = p.position.y() - s.sufferer.y();
            const double r2 = (dx * dx + dy * dy) / (e.length_m * e.length_m);
            w[2] -= e.coefficient * p.jet.thrust_n * std::exp(-r2);
        }
        return w;
    }
    bool acts_far_from_jets() const override { return true; }  // the jets that hit the floor come back everywhere
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        of(e).enabled = on;
        of(e).coefficient = v[0];
    }
    std::vector<double> values(const Effects& e) const override { return {of(e).coefficient}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        EffectType::keys(k, e);
        k.number("length_m", of(e).length_m, {0.01, 100});
    }
    std::optional<CoverageCase> coverage_case() const override { return CoverageCase{"stack", {{0.01, 0.08}}}; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat(
            "**floor_recirculation** — jets hitting the floor come back as a bias that grows with the jets impinging "
            "(coefficient ",
            fixed(v[0], 3), "). ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_floor_recirculation() { return std::make_unique<FloorRecirculation>(); }

}  // namespace dw::physics::effects
