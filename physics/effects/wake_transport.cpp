// wake_transport: the downwash's descent time (stage: air): each jet's air at the sufferer follows
// its producer's state delay_scale × its descent time ago (the wrench model's jets carry the delay).
#include <cmath>

#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

struct WakeTransportSettings {
    bool enabled = false;
    double delay_scale = 1.0;
};

class WakeTransport final : public OneNumber<WakeTransportSettings> {
public:
    WakeTransport() : OneNumber("wake_transport", &WakeTransportSettings::delay_scale) {}
    int vocabulary_place() const override { return 3; }  // ../shared/FLIGHT_FORMAT.md
    const EffectFamily* family() const override { return &kDelayFamily; }
    std::vector<EffectParameter> parameters() const override {
        return {{"delay_scale", "", 0, 10, 0.0, 5.0, range(0.0, 3.0, 7), 1.0}};
    }
    bool changes_flow() const override { return true; }
    double transport_delay_scale(const Effects& e) const override { return of(e).delay_scale; }
    std::optional<ProofCase> proof_case() const override {
        return ProofCase{"leader_follower", "wake transport delay (jet law, scale 1)", {1.0}, {}, 12};
    }
    std::optional<CoverageCase> coverage_case() const override { return CoverageCase{"leader_follower", {{0.5, 2.0}}}; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat(
            "**wake_transport** — the downwash takes time to descend: the force follows each neighbour's state ",
            fixed(v[0], 2),
            " × τ(s) ago, τ(s) the turbulent jet's descent time over the vertical separation s (146 ms at 1.3 m for ",
            "k = 1). The simulation had the force follow the neighbour instantly. Its signature: the time shift grows "
            "with separation. ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_wake_transport() { return std::make_unique<WakeTransport>(); }

}  // namespace dw::physics::effects
