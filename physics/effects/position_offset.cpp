// position_offset: the neighbours' motion-capture frame offset from the sufferer's (stage: positions).
#include <cmath>

#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

struct PositionOffsetSettings {
    bool enabled = false;
    std::array<double, 3> offset_m{0, 0, 0};
};

class PositionOffset final : public BuiltIn<PositionOffsetSettings> {
public:
    PositionOffset() : BuiltIn("position_offset") {}
    int vocabulary_place() const override { return 4; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override {
        std::vector<EffectParameter> p;
        for (const char* axis : {"offset_n_m", "offset_e_m", "offset_d_m"})
            p.push_back({axis, "m", -10, 10, -0.3, 0.3, {}, 0.0});
        return p;
    }
    bool changes_flow() const override { return true; }
    std::string grouped_key() const override { return "offset_m"; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        of(e) = {on, {v[0], v[1], v[2]}};
    }
    std::vector<double> values(const Effects& e) const override {
        return {of(e).offset_m.begin(), of(e).offset_m.end()};
    }
    void keys(KeyVisitor& k, Effects& e) const override {
        auto& x = of(e);
        k.flag("enabled", x.enabled);
        const auto p = parameters().front();  // the three axes share their bounds
        k.numbers(grouped_key(), x.offset_m, {p.config_min, p.config_max, "m"}, "expected [n, e, d] in metres");
    }
    Stage stage() const override { return Stage::positions; }
    std::array<double, 3> position_error_m(const Effects& e) const override { return of(e).offset_m; }
    std::optional<CoverageCase> coverage_case() const override {
        return CoverageCase{"single", {{-0.1, 0.1}, {-0.1, 0.1}, {-0.1, 0.1}}};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat(
            "**position_offset** — the neighbours' motion-capture frame is offset from the sufferer's by (",
            fixed(v[0], 3), ", ", fixed(v[1], 3), ", ", fixed(v[2], 3),
            ") m (N, E, D): the force pattern sits off the recorded positions by a fixed distance, the same ",
            who.flying ? "whichever way the neighbour passes" : "on +E and −E legs", ". ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_position_offset() { return std::make_unique<PositionOffset>(); }

}  // namespace dw::physics::effects
