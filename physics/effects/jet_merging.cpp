// jet_merging: neighbouring jets merging into one column (stage: air): jets whose half-widths
// overlap merge into one momentum-conserving, contracted jet on their momentum-weighted axis.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "physics/effects/common.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics::effects {
namespace {

// Which producers' jets merge at the sufferer's depth: pairs whose half-widths overlap, joined
// transitively. Each producer's group (its lowest member) and its merging weight (0-1).
struct MergeGroups {
    std::vector<int> group;
    std::vector<double> weight;
};

MergeGroups merge_groups(const Vec3& suf, std::span<const Producer> producers, double onset, double full) {
    const std::size_t k = producers.size();
    std::vector<int> group(k);
    std::iota(group.begin(), group.end(), 0);
    std::vector<double> weight(k, 0.0);
    auto root = [&](int i) {
        while (group[static_cast<std::size_t>(i)] != i) i = group[static_cast<std::size_t>(i)];
        return i;
    };
    std::vector<Vec3> centre(k);
    std::vector<double> half(k), depth(k);
    for (std::size_t j = 0; j < k; ++j) {
        depth[j] = (suf - producers[j].position).dot(producers[j].axis);
        centre[j] = producers[j].position + depth[j] * producers[j].axis;
        half[j] = producers[j].jet.half_width(depth[j]);
    }
    for (std::size_t a = 0; a < k; ++a) {
        for (std::size_t b = a + 1; b < k; ++b) {
            if (depth[a] <= 0 || depth[b] <= 0) continue;
            const double d = std::max((centre[a] - centre[b]).norm(), 1e-6);
            const double o = (half[a] + half[b]) / d;
            double w = std::clamp((o - onset) / (full - onset), 0.0, 1.0);
            w = w * w * (3 - 2 * w);  // smoothstep: no kink where merging begins
            if (w <= 0) continue;
            const int ra = root(static_cast<int>(a)), rb = root(static_cast<int>(b));
            group[static_cast<std::size_t>(std::max(ra, rb))] = std::min(ra, rb);
            weight[a] = std::max(weight[a], w);
            weight[b] = std::max(weight[b], w);
        }
    }
    for (std::size_t j = 0; j < k; ++j) group[j] = root(static_cast<int>(j));
    return {group, weight};
}

// Momentum flux adds; the merged axis sits at the momentum-weighted centroid; the column contracts
// by kappa with its centreline speed raised by 1/kappa so that momentum is conserved.
Producer merged(std::span<const Producer> producers, const std::vector<int>& members, double kappa) {
    Producer m;
    m.position.setZero();
    m.axis.setZero();
    m.velocity.setZero();
    m.gust = 0;
    double total = 0, uh2 = 0, c_half = 0, l = 0;
    for (int i : members) {
        const Producer& p = producers[static_cast<std::size_t>(i)];
        const double w = p.jet.thrust_n;
        total += w;
        m.position += w * p.position;
        m.axis += w * p.axis;
        m.velocity += w * p.velocity;
        m.gust += w * p.gust;
        uh2 += p.jet.u_hover * p.jet.u_hover;
        c_half += w * p.jet.c_half;
        l += w * p.jet.l;
    }
    m.position /= total;
    m.axis.normalize();
    m.velocity /= total;
    m.gust /= total;
    m.jet = producers[static_cast<std::size_t>(members.front())].jet;
    m.jet.model = JetModelKind::bauersfeld;
    m.jet.thrust_n = total;
    m.jet.u_hover = std::sqrt(uh2);
    m.jet.l = l / total;
    m.jet.inv_l = 1.0 / m.jet.l;
    m.jet.k_centre = m.jet.u_hover * m.jet.k.strength / kappa;
    m.jet.c_half = kappa * c_half / total;
    return m;
}

struct JetMergingSettings {
    bool enabled = false;
    double contraction = 0.8;
    double onset = 0.6;  // the jets' overlap (half-widths over distance) where merging begins
    double full = 1.0;   // and where it is complete
};

// Each group's jets at the weight left them by merging, then the group merged at its weight.
void regroup(const AirScene& s, const JetMergingSettings& jm, std::vector<WeightedProducer>& out) {
    const std::size_t k = s.producers.size();
    const auto [group, weight] = merge_groups(s.sufferer, s.producers, jm.onset, jm.full);
    for (std::size_t g = 0; g < k; ++g) {
        std::vector<int> members;
        double w_merge = 0;
        for (std::size_t j = 0; j < k; ++j) {
            if (static_cast<std::size_t>(group[j]) == g) {
                members.push_back(static_cast<int>(j));
                w_merge = std::max(w_merge, weight[j]);
            }
        }
        if (members.empty()) continue;
        const double w_single = members.size() > 1 ? 1.0 - w_merge : 1.0;
        for (int j : members) out.push_back({s.producers[static_cast<std::size_t>(j)], w_single});
        if (members.size() > 1 && w_merge > 0) out.push_back({merged(s.producers, members, jm.contraction), w_merge});
    }
}

class JetMerging final : public BuiltIn<JetMergingSettings> {
public:
    JetMerging() : BuiltIn("jet_merging") {}
    int vocabulary_place() const override { return 7; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override {
        return {{"contraction", "", 0.05, 2, 0.05, 1.0, range(0.2, 1.0, 5), 0.8}};
    }
    bool changes_flow() const override { return true; }
    bool regroups_jets() const override { return true; }
    void regroup_jets(const Effects& e, const AirScene& s, std::vector<WeightedProducer>& out) const override {
        regroup(s, of(e), out);
    }
    const EffectFamily* family() const override { return &kPushFamily; }
    bool applies(int neighbours, bool) const override { return neighbours >= 2; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        of(e).enabled = on;
        of(e).contraction = v[0];
    }
    std::vector<double> values(const Effects& e) const override { return {of(e).contraction}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        EffectType::keys(k, e);
        auto& x = of(e);
        k.number("onset", x.onset, {0, 10});
        k.number("full", x.full, {0, 10});
        k.require(x.full > x.onset, "full", "must be greater than onset");
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
