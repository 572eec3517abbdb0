#pragma once
// The candidate effects of the registered vocabulary (physics/effect_types.hpp) as fittable
// terms: each has named parameters with the bounds the explainer searches and a starting point,
// and switches itself on in a physics configuration. Names and parameter names are the contract's.
#include <string>
#include <vector>

#include "physics/config.hpp"
#include "physics/effect_types.hpp"

namespace dw::analysis {

// A parameter is the type's own (physics::EffectParameter): the fit searches [fit_min, fit_max]
// from `start`, after trying `grid`.
using Parameter = physics::EffectParameter;

struct Effect {
    const physics::EffectType* type = nullptr;
    std::string name;
    std::vector<Parameter> params;
    // The axes of an effect that acts between two (type->has_axes()), chosen before the fit — by
    // the explainer from the residual, unless given (axes_given: a proof asks about these axes).
    int from = 2, to = 0;
    bool axes_given = false;
    // Switches the effect on in c with these parameter values.
    void apply(physics::PhysicsConfig& c, const std::vector<double>& values) const;
    // The neutral values (the effect absent).
    std::vector<double> neutral() const;
    // Whether intervals [lo, hi] (one per parameter) hold the neutral values, every one. Where the
    // neutral values are the effect's absence, the data cannot tell the effect from no effect, and
    // it is never accepted.
    bool holds_neutral(const std::vector<double>& lo, const std::vector<double>& hi) const;
    // Whether evaluating it needs the physics again (flow effects) or only the recording's view.
    bool changes_flow() const { return type->changes_flow(); }
};

// Every registered candidate, in the registry's order.
std::vector<Effect> all_effects();
// The named candidates; throws dw::InputError naming an unknown one and the known ones.
std::vector<Effect> effects_named(const std::vector<std::string>& names);

}  // namespace dw::analysis
