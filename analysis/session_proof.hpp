#pragma once
// The session's proof on recorded flights (another lab's: their physics is not the truth there).
// The flights are grouped into sessions; each session is first explained as it is (its own fit of
// the rig), then again on top of that fit — where it must claim nothing new. Then each effect of
// the rig is concealed in every flight of the session at a size one flight alone rarely shows
// (each row says on how many flights the single-flight explainer accepts it), and the session is
// explained on top of its own fit: the effect must be accepted with the expected value (the own
// fit's combined with the concealed one) inside its interval — or, for an effect of a family, the
// family named with it — and nothing else claimed.
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

#include "analysis/conceal.hpp"
#include "physics/config.hpp"

namespace dw::analysis {

// Ten: the shared trials' rig effects differ from trial to trial by nature (gains by about 0.2,
// the random walks' delays by about 0.04 s), and five flights do not resolve a shift of the size
// concealed below what one flight shows (docs/REAL.md, "Sessions": 12 and 9 of 16 at five).
inline constexpr std::size_t kDefaultSessionSize = 10;
// The share of concealed sessions in which the effect must be recovered.
inline constexpr double kSessionRecoveryTarget = 0.9;

struct SessionProofOptions {
    std::vector<std::string> flights;  // flight folders; those with a neighbour are grouped (sessions_of)
    physics::PhysicsConfig physics;
    std::string out_dir;
    std::size_t session_size = kDefaultSessionSize;
    std::size_t max_sessions = 0;    // 0: every full group
    bool interleave = false;         // deal the flights into the sessions in turn, not in order
    std::vector<std::string> cases;  // concealment_names() (empty: all)
    // How much of each effect it conceals: below what one of the shared flights shows alone
    // (docs/REAL.md, "Sessions"; the options, e.g. `--clock`, probe other sizes).
    Concealed concealed = concealed_sizes(ConcealedSize::session);
    std::stop_token stop;
    std::function<void(const std::string&)> progress;
};

struct SessionProofRow {
    std::string session, concealed, expected, found, fitted;
    std::size_t alone = 0, flights = 0;  // flights on which one flight alone accepts the concealed effect
    bool untouched = false, pass = false, family_named = false;
    std::string why;
};

struct SessionProofResult {
    std::vector<SessionProofRow> rows;
    std::size_t recovered = 0, concealed = 0, clean = 0, untouched = 0;
    bool pass = false;
    std::string table_path;
};

inline constexpr const char* kSessionProofTableFile = "session_proof.md";
SessionProofResult run_session_proof(const SessionProofOptions& o);

}  // namespace dw::analysis
