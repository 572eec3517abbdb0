// jet_merging: neighbouring jets merging into one column (stage: air; its physics is wrench_model's).
#include <cmath>

#include "physics/effects/builtins.hpp"
#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

class JetMerging final : public EffectType {
public:
    std::string name() const override { return "jet_merging"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"contraction", "", 0.05, 2, 0.05, 1.0, range(0.2, 1.0, 5), 0.8}};
    }
    bool changes_flow() const override { return true; }
    const EffectFamily* family() const override { return &kPushFamily; }
    bool applies(int neighbours, bool) const override { return neighbours >= 2; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        e.jet_merging.enabled = on;
        e.jet_merging.contraction = v[0];
    }
    void clear(Effects& e) const override { e.jet_merging = {}; }
    bool enabled(const Effects& e) const override { return e.jet_merging.enabled; }
    std::vector<double> values(const Effects& e) const override { return {e.jet_merging.contraction}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        EffectType::keys(k, e);
        k.number("onset", e.jet_merging.onset, {0, 10});
        k.number("full", e.jet_merging.full, {0, 10});
        k.require(e.jet_merging.full > e.jet_merging.onset, "full", "must be greater than onset");
    }
    std::optional<ProofCase> proof_case() const override {
        return ProofCase{"leader_follower3", "jet merging (only where jets overlap: K = 3, >= 1 m)", {0.8}, {}, 14};
    }
    std::optional<CoverageCase> coverage_case() const override {
        return CoverageCase{"leader_follower3", {{0.5, 0.95}}};
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat(
            "**jet_merging** — neighbouring jets merge into one contracted, momentum-conserving column where their "
            "half-widths overlap (contraction ",
            fixed(v[0], 2), "): the aggregate is not the sum of single jets. It acts only with ",
            "two or more neighbours close together and far enough above the sufferer for the jets to widen. ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_jet_merging() { return std::make_unique<JetMerging>(); }

}  // namespace dw::physics::effects
