#pragma once
// The explainer's proof: flights made by `dw-sim fly` with one effect (or two) hidden in the
// physics, explained with the plain physics, and checked — the right effect named, the true
// parameter inside the reported interval, the held-out error reduced; null flights (noise only)
// must name nothing in at least 9 of 10 seeds.
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

#include "analysis/conceal.hpp"
#include "physics/config.hpp"
#include "physics/trajectory.hpp"

namespace dw::analysis {

struct ProofOptions {
    std::string out_dir;
    int null_seeds = 10;
    std::vector<std::string> cases;  // empty: all (proof_case_list); an unknown name is a dw::InputError
    int jobs = 2;                    // flights flown and explained at once
    std::stop_token stop;            // between flights and fits: dw::Stopped
    std::function<void(const std::string&)> progress;
};

struct ProofRow {
    std::string name, formation, hidden, found, truth, fitted, rmse;
    bool pass = false;
    bool covered = true;  // every true value inside the interval of its fit, accepted or not
    std::string why;
    double seconds = 0;
    // Not accepted only because the flight cannot carry the held-out test (too few pieces hold its
    // evidence: CandidateResult::too_few_pieces), and fitted right.
    bool not_identifiable = false;
    // Not accepted as itself, but its family named (ExplainResult::families): the flight could not
    // tell the members apart, and the report says so — never another member alone.
    bool family_named = false;
};

struct ProofResult {
    std::vector<ProofRow> rows;
    int null_clean = 0, null_total = 0;
    std::vector<std::string> skipped;  // real-proof: flights without a neighbour (nothing near to conceal an effect in)
    bool pass = false;
    std::string table_path;
};

// The proofs' table, in their output folder.
inline constexpr const char* kProofTableFile = "proof.md";
// The proof's cases, comma-separated: "null", each effect's own (EffectType::proof_case), "two_effects".
std::string proof_case_list();
ProofResult run_proof(const ProofOptions& o);

// A flight simulated as `dw-sim fly` flies it (the simulator as a library), with this physics
// hidden in it, into the flight folder dir; the hidden physics beside it (dir.physics.yaml). A
// stop request stops it (dw::Stopped).
void fly_simulated(const physics::PhysicsConfig& hidden, const std::string& formation, std::uint64_t seed,
                   const std::string& dir, const std::stop_token& stop, int legs = physics::GridOptions{}.legs);

// The proof on recorded flights (another lab's: the physics is not the truth there). Each flight
// is first explained as it is — its own fit, whatever the real data shows. Known effects are then
// concealed in its recording (each effect of the rig that declares a concealment; values not round)
// and explained with that own fit as the physics: each must be found on top of it, its parameter
// (the own fit's combined with the concealed value) inside the interval, nothing else claimed; and
// the untouched flight explained on top of its own fit must claim nothing new.
struct RealProofOptions {
    std::vector<std::string> flights;  // flight folders
    physics::PhysicsConfig physics;    // what the untouched flights are first explained with
    std::string out_dir;
    std::vector<std::string> cases;  // concealment_names() (empty: all)
    Concealed concealed = concealed_sizes(ConcealedSize::single);
    std::stop_token stop;
    std::function<void(const std::string&)> progress;
};
ProofResult run_real_proof(const RealProofOptions& o);

}  // namespace dw::analysis
