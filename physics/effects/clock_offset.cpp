// clock_offset: the wrench's clock against the poses' (stage: clock).
#include <cmath>

#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

struct ClockOffsetSettings {
    bool enabled = false;
    double offset_s = 0.0;
};

class ClockOffset final : public OneNumber<ClockOffsetSettings> {
public:
    ClockOffset() : OneNumber("clock_offset", &ClockOffsetSettings::offset_s) {}
    int vocabulary_place() const override { return 1; }  // ../shared/FLIGHT_FORMAT.md
    const EffectFamily* family() const override { return &kDelayFamily; }
    std::optional<std::vector<double>> from_family_quantity(double shift_s) const override {
        return std::vector<double>{shift_s};  // the stamps run late by the shift itself
    }
    std::vector<EffectParameter> parameters() const override {
        return {{"offset_s", "s", -10, 10, -0.5, 0.5, range(-0.3, 0.3, 25), 0.0}};
    }
    Stage stage() const override { return Stage::clock; }
    double clock_delay_s(const Effects& e) const override { return of(e).offset_s; }
    std::optional<ProofCase> proof_case() const override {
        return ProofCase{"single", "clock offset 0.1 s (legs both ways; the maps look right)", {0.1}, {}, 11};
    }
    std::optional<CoverageCase> coverage_case() const override { return CoverageCase{"single", {{-0.15, 0.15}}}; }
    std::optional<std::vector<double>> in_two_effects_case() const override { return std::vector<double>{0.08}; }
    std::optional<RealConcealment> real_concealment() const override {
        return RealConcealment{
            "--clock", "the wrench stamped this late [s]", {0.001, 2, "s"}, 0.083, 0.031, false, {}, "wrench stamped ",
            " s late"};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat("**clock_offset** — ", who.clock, " is ", fixed(std::abs(v[0]), 3), " s ",
                        v[0] >= 0 ? "behind" : "ahead of",
                        " the poses': the force on the sufferer at pose time t is stamped t ", v[0] >= 0 ? "+ " : "− ",
                        fixed(std::abs(v[0]), 3),
                        " s in wrench.csv. Nothing aerodynamic is missing; the two time bases differ. At 0.5 m/s it ",
                        "moves the force pattern ", fixed(std::abs(v[0]) * 50, 1), " cm ", who.along,
                        " — while the time shift is the same at every separation (table of shifts). ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_clock_offset() { return std::make_unique<ClockOffset>(); }

}  // namespace dw::physics::effects
