#pragma once
// The candidate effects of ../shared/FLIGHT_FORMAT.md's vocabulary, as fittable terms: each has
// named parameters with bounds and a starting point, and switches itself on in a physics
// configuration. Names and parameter names are the contract's.
#include <string>
#include <vector>

#include "physics/config.hpp"

namespace dw::analysis {

struct Parameter {
    std::string name;
    double lower = 0, upper = 0;
    std::vector<double> grid;  // starting points tried before the local fit (may be empty)
    double start = 0;
};

struct Effect {
    std::string name;
    std::vector<Parameter> params;
    // cell_crosstalk's axes, chosen before the fit (the pair whose residual the other axis explains best).
    int from = 2, to = 0;
    // Switches the effect on in c with these parameter values.
    void apply(physics::PhysicsConfig& c, const std::vector<double>& values) const;
    // The effect's parameters as set in c (its values if enabled, else the neutral ones).
    std::vector<double> neutral() const;
    // Whether evaluating it needs the physics again (flow effects) or only the recording's view.
    bool changes_flow() const;
};

// Every candidate, in the vocabulary's order.
std::vector<Effect> all_effects();
// The named candidates; throws dw::InputError naming an unknown one.
std::vector<Effect> effects_named(const std::vector<std::string>& names);

}  // namespace dw::analysis
