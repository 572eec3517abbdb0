// Issue 73: a flow effect defined in one file (toy_flow_effect.cpp) is read from a configuration,
// acts where the air is evaluated, is simulated, fitted by the explainer and reported, without any
// other file naming it: through the libraries, and through the shipped dw-sim, which loads that
// file built as an effect module (DW_EFFECT_MODULES). Its own test executable, so that the other
// tests' vocabulary stays the contract's.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "analysis/explain.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "physics/effect_types.hpp"
#include "physics/flight_sim.hpp"
#include "support.hpp"
#include "toy_support.hpp"

namespace {

using namespace dw::physics;

constexpr double kFraction = 0.3;

std::string outwash_yaml() { return dw::test::one_effect_yaml("toy_outwash", "fraction", kFraction); }

using dw::test::fly_toy;

// The largest change of an axis between two simulations of the same flight.
double largest_change(const dw::flight::Flight& a, const dw::flight::Flight& b, std::size_t axis) {
    double most = 0;
    for (std::size_t i = 0; i < a.wrench.size(); ++i)
        most = std::max(most, std::abs(a.wrench[i].w[axis] - b.wrench[i].w[axis]));
    return most;
}

}  // namespace

TEST(FlowEffect, AToyFlowEffectIsSimulatedWhereTheAirIsAndExplained) {
    const PhysicsConfig c = parse_physics(outwash_yaml(), "outwash.yaml");
    ASSERT_EQ(c.effects.extra.count("toy_outwash"), 1u);
    EXPECT_TRUE(effect_type("toy_outwash").changes_flow());
    const auto plain = fly_toy(PhysicsConfig{}), outwash = fly_toy(c);
    ASSERT_EQ(plain.wrench.size(), outwash.wrench.size());
    // The same flight: its push is lateral only, and there only where a jet passes above.
    EXPECT_EQ(largest_change(plain, outwash, 2), 0.0);
    EXPECT_GT(largest_change(plain, outwash, 0) + largest_change(plain, outwash, 1), 0.02);

    dw::analysis::ExplainOptions o;  // the lab's physics, without it; every registered candidate
    const auto r = dw::analysis::explain(outwash, o);
    ASSERT_EQ(r.accepted.size(), 1u) << "only the outwash explains it";
    const auto& found = r.accepted.front();
    EXPECT_EQ(found.effect.name, "toy_outwash");
    EXPECT_LE(found.lo.at(0), kFraction);
    EXPECT_GE(found.hi.at(0), kFraction);
    EXPECT_NE(found.effect.type->describe(found.values, {}, {}).find("**toy_outwash**"), std::string::npos);
}

TEST(FlowEffect, TheShippedSimulatorLoadsItAsAModule) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("outwash.yaml")) << outwash_yaml();
    std::vector<std::string> args{dw::test::bin("dw-sim")};
    args.insert(args.end(), dw::test::kToyFlightArgs.begin(), dw::test::kToyFlightArgs.end());
    args.insert(args.end(), {"--physics", dir.file("outwash.yaml"), "--quiet", "--out", dir.file("f")});
    const auto r = dw::test::run(args, dir, std::chrono::minutes(2),
                                 {std::string(kEffectModulesVariable) + "=" + DW_TOY_FLOW_MODULE});
    ASSERT_EQ(r.status, 0) << r.err;
    const auto shipped = dw::flight::read_flight(dir.file("f"));
    const auto here = fly_toy(parse_physics(outwash_yaml(), "outwash.yaml"));
    ASSERT_EQ(shipped.wrench.size(), here.wrench.size());
    // The same wrench as simulated here (flight folders keep 6 decimals), the outwash in it.
    for (std::size_t axis = 0; axis < 3; ++axis) EXPECT_LE(largest_change(shipped, here, axis), 1e-6) << axis;
    const auto plain = fly_toy(PhysicsConfig{});
    EXPECT_GT(largest_change(shipped, plain, 0) + largest_change(shipped, plain, 1), 0.02);
}
