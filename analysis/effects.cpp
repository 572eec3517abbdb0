#include "analysis/effects.hpp"

namespace dw::analysis {

namespace {
Effect candidate(const physics::EffectType& t) { return Effect{&t, t.name(), t.parameters()}; }
}  // namespace

std::vector<Effect> all_effects() {
    std::vector<Effect> out;
    for (const auto* t : physics::effect_types()) out.push_back(candidate(*t));
    return out;
}

std::vector<Effect> effects_named(const std::vector<std::string>& names) {
    std::vector<Effect> out;
    for (const auto& n : names) out.push_back(candidate(physics::effect_type(n, "--effects")));
    return out;
}

std::vector<double> Effect::neutral() const {
    std::vector<double> v;
    for (const auto& p : params) v.push_back(p.start);
    return v;
}

bool Effect::holds_neutral(const std::vector<double>& lo, const std::vector<double>& hi) const {
    const auto n = neutral();
    if (lo.size() != n.size() || hi.size() != n.size()) return false;
    for (std::size_t k = 0; k < n.size(); ++k)
        if (n[k] < lo[k] || n[k] > hi[k]) return false;
    return true;
}

void Effect::apply(physics::PhysicsConfig& c, const std::vector<double>& v) const {
    type->set(c.effects, v, {from, to});
}

}  // namespace dw::analysis
