// Issue 17: an effect defined in one file (toy_effect.cpp) is read from a configuration, simulated,
// fitted by the explainer and written in its report, without any other file naming it: through
// the libraries, and (issue 44) through the shipped dw-sim and dw-explain, which load that file
// built as an effect module (DW_EFFECT_MODULES). It lives in its own test executable so that the
// other tests' vocabulary stays the contract's.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>

#include "analysis/explain.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "physics/effect_types.hpp"
#include "physics/flight_sim.hpp"
#include "support.hpp"
#include "toy_support.hpp"

namespace {

using namespace dw::physics;

constexpr double kBias = 0.137;

std::string toy_yaml() { return dw::test::one_effect_yaml("toy_lateral_bias", "bias_n", kBias); }
PhysicsConfig with_toy() { return parse_physics(toy_yaml(), "toy.yaml"); }

// The shipped programs with the toy effect's file built as an effect module.
const std::vector<std::string> kWithToyModule{std::string(dw::physics::kEffectModulesVariable) + "=" + DW_TOY_MODULE};

using dw::test::fly_toy;

}  // namespace

TEST(EffectRegistry, AToyEffectIsConfiguredLikeTheVocabulary) {
    const PhysicsConfig c = with_toy();
    ASSERT_EQ(c.effects.extra.count("toy_lateral_bias"), 1u);
    EXPECT_DOUBLE_EQ(c.effects.extra.at("toy_lateral_bias").at(0), kBias);
    EXPECT_EQ(parse_physics(to_yaml(c), "back.yaml").effects.extra, c.effects.extra) << to_yaml(c);
    EXPECT_NE(to_yaml(PhysicsConfig{}).find("toy_lateral_bias"), std::string::npos)
        << "written, switched off, like every effect";
    try {
        parse_physics("format: downwash-physics/1\neffects:\n  toy_lateral_bia:\n    enabled: true\n", "typo.yaml");
        ADD_FAILURE() << "an unknown effect was accepted";
    } catch (const dw::InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("typo.yaml:3:"), std::string::npos) << what;
        EXPECT_NE(what.find("unknown key 'toy_lateral_bia': no such effect"), std::string::npos) << what;
        EXPECT_NE(what.find("toy_lateral_bias"), std::string::npos) << "the known ones are listed: " << what;
    }
    EXPECT_THROW(parse_physics("effects:\n  toy_lateral_bias:\n    bias_n: 3\n", "big.yaml"), dw::InputError)
        << "its bounds are checked";
}

TEST(EffectRegistry, AToyEffectIsSimulatedExplainedAndReported) {
    dw::test::TempDir dir;
    const auto plain = fly_toy(PhysicsConfig{}), toy = fly_toy(with_toy());
    ASSERT_EQ(plain.wrench.size(), toy.wrench.size());
    for (std::size_t i = 0; i < toy.wrench.size(); ++i) {  // the same flight, with the bias on f_e alone
        EXPECT_NEAR(toy.wrench[i].w[1] - plain.wrench[i].w[1], kBias, 1e-9);
        EXPECT_EQ(toy.wrench[i].w[2], plain.wrench[i].w[2]);
    }
    dw::analysis::ExplainOptions o;  // the lab's physics, without the toy; every registered candidate
    const auto r = dw::analysis::explain(toy, o);
    dw::analysis::write_report(toy, r, o, dir.file("out"));
    ASSERT_EQ(r.accepted.size(), 1u) << "only the toy explains it";
    const auto& c = r.accepted.front();
    EXPECT_EQ(c.effect.name, "toy_lateral_bias");
    // On top of what the untouched flight shows of it: its tare (the mean of 2 s of noise) leaves
    // a steady f_e of its own, about 0.008 N here, which a bias candidate finds too.
    dw::analysis::ExplainOptions just_toy;
    just_toy.candidates = dw::analysis::effects_named({"toy_lateral_bias"});
    const auto untouched = dw::analysis::explain(plain, just_toy);
    ASSERT_EQ(untouched.candidates.size(), 1u);
    const double expected = kBias + untouched.candidates.front().values.at(0);
    EXPECT_LE(c.lo.at(0), expected);
    EXPECT_GE(c.hi.at(0), expected);
    EXPECT_NEAR(c.values.at(0), kBias, 0.02);
    const auto md = dw::read_file(dir.file("out/report.md"));
    EXPECT_NE(md.find("**toy_lateral_bias** — the stand reads a steady"), std::string::npos) << md;
    const auto j = nlohmann::json::parse(dw::read_file(dir.file("out/report.json")));
    EXPECT_EQ(j["explained_by"][0], "toy_lateral_bias");
    bool listed = false;
    for (const auto& cand : j["candidates"])
        listed = listed || (cand["effect"] == "toy_lateral_bias" && cand["params"].contains("bias_n"));
    EXPECT_TRUE(listed) << j["candidates"].dump();
}

TEST(EffectRegistry, TheShippedProgramsLoadItAsAModuleFlyExplainAndReportIt) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("toy.yaml")) << toy_yaml();
    std::vector<std::string> fly_args = dw::test::kToyFlightArgs;
    fly_args.insert(fly_args.end(), {"--physics", dir.file("toy.yaml"), "--quiet", "--out"});
    auto args = [&](const std::string& exe, const std::string& out) {
        std::vector<std::string> a{exe};
        a.insert(a.end(), fly_args.begin(), fly_args.end());
        a.push_back(out);
        return a;
    };
    // Without the module dw-sim does not know it: the vocabulary stays the contract's.
    dw::test::expect_one_line_exit_2(dw::test::run(args(dw::test::bin("dw-sim"), dir.file("plain")), dir),
                                     "unknown key 'toy_lateral_bias': no such effect");
    // A module that is not there: one line, exit 2.
    dw::test::expect_one_line_exit_2(
        dw::test::run(args(dw::test::bin("dw-sim"), dir.file("none")), dir, std::chrono::minutes(2),
                      {std::string(dw::physics::kEffectModulesVariable) + "=" + dir.file("missing.so")}),
        "cannot load effect module");
    auto r = dw::test::run(args(dw::test::bin("dw-sim"), dir.file("f")), dir, std::chrono::minutes(2), kWithToyModule);
    ASSERT_EQ(r.status, 0) << r.err;
    r = dw::test::run({dw::test::bin("dw-explain"), "--real", dir.file("f"), "--out", dir.file("o"), "--quiet"}, dir,
                      std::chrono::minutes(10), kWithToyModule);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("explained by: toy_lateral_bias"), std::string::npos) << r.out;
    const auto j = nlohmann::json::parse(dw::read_file(dir.file("o/report.json")));
    ASSERT_EQ(j["explained_by"].size(), 1u) << j["explained_by"].dump();
    EXPECT_EQ(j["explained_by"][0], "toy_lateral_bias");
    EXPECT_NE(dw::read_file(dir.file("o/report.md")).find("**toy_lateral_bias** — the stand reads a steady"),
              std::string::npos);
    const auto fitted = load_physics(dir.file("o/physics.yaml"));  // dw-explain's physics, read by this test's
    ASSERT_EQ(fitted.effects.extra.count("toy_lateral_bias"), 1u);
    EXPECT_NEAR(fitted.effects.extra.at("toy_lateral_bias").at(0), kBias, 0.02);
}

// Issue 73: a built-in effect is named (as a word, comments included) only in its own file; every other product source file (not the tests, benchmarks or docs)
// reaches it through the registry — its settings, its physics at its stage, its proof,
// concealment and coverage cases all live in its file.
TEST(EffectRegistry, ABuiltInIsNamedOnlyInItsOwnFile) {
    namespace fs = std::filesystem;
    std::vector<std::string> names;
    for (const auto& t : builtin_effects()) names.push_back(t->name());
    const fs::path root = DW_SOURCE_DIR;
    const std::set<std::string> kNotProduct{"tests", "bench", "docs", "config", "scripts", "cmake", ".git"};
    std::map<std::string, std::set<std::string>> found;
    for (const auto& top : fs::directory_iterator(root)) {
        const auto folder = top.path().filename().string();
        if (!top.is_directory() || kNotProduct.count(folder) || folder.starts_with("build")) continue;
        for (const auto& f : fs::recursive_directory_iterator(top.path())) {
            const auto ext = f.path().extension().string();
            if (!f.is_regular_file() || (ext != ".cpp" && ext != ".hpp" && ext != ".in")) continue;
            const auto rel = fs::relative(f.path(), root).string();
            const std::string text = dw::read_file(f.path().string());
            for (const auto& n : names)
                if (rel != "physics/effects/" + n + ".cpp" && std::regex_search(text, std::regex("\\b" + n + "\\b")))
                    found[rel].insert(n);
        }
    }
    for (const auto& [file, effects] : found)
        ADD_FAILURE() << file << " names the built-in effects " << dw::log::join(effects)
                      << ": reach them through the registry (physics/effect_types.hpp)";
    EXPECT_GE(names.size(), 10u) << "every built-in is looked for";
}
