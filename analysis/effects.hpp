#pragma once
// The candidate effects of the registered vocabulary (physics/effect_types.hpp) as fittable
// terms: each has named parameters with the bounds the explainer searches and a starting point,
// and switches itself on in a physics configuration. Names and parameter names are the contract's.
#include <string>
#include <vector>

#include "physics/config.hpp"
#include "physics/effect_types.hpp"

namespace dw::analysis {

struct Parameter {
    std::string name;
    double lower = 0, upper = 0;
    std::vector<double> grid;  // starting points tried before the local fit (may be empty)
    double start = 0;
};

struct Effect {
    const physics::EffectType* type = nullptr;
    std::string name;
    std::vector<Parameter> params;
    // The axes of an effect that acts between two (type->has_axes()), chosen before the fit.
    int from = 2, to = 0;
    // Switches the effect on in c with these parameter values.
    void apply(physics::PhysicsConfig& c, const std::vector<double>& values) const;
    // The neutral values (the effect absent).
    std::vector<double> neutral() const;
    // Whether evaluating it needs the physics again (flow effects) or only the recording's view.
    bool changes_flow() const { return type->changes_flow(); }
};

// Every registered candidate, in the registry's order.
std::vector<Effect> all_effects();
// The named candidates; throws dw::InputError naming an unknown one and the known ones.
std::vector<Effect> effects_named(const std::vector<std::string>& names);

}  // namespace dw::analysis
