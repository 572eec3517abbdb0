#pragma once
// The explainer's proof on mismatches the vocabulary has no word for (issue 68): flights made by
// `dw-sim fly` (the simulator as a library), then something hidden in them that no effect names —
// a zero or a gain that creeps over the flight, a sensor that stops following large forces, wakes
// that move sideways as they fall, a jet wider than the model's, a gain that changes with the
// direction of travel, a periodic disturbance that grows with the force, another jet, another
// aggregation — explained with the plain physics. Each must be detected, no effect of the vocabulary
// accepted for it, and what is left modelled by the learnt discrepancy (its held-out improvement in
// the report). Null flights (noise and turbulence only) must stay clean.
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

namespace dw::analysis {

struct UnnamedOptions {
    std::string out_dir;
    std::vector<std::string> cases;  // empty: all (unnamed_case_list); an unknown name is a dw::InputError
    int legs = 36;                   // legs per flight
    int null_seeds = 10;
    int jobs = 2;
    std::stop_token stop;
    std::function<void(const std::string&)> progress;
};

struct UnnamedRow {
    std::string name, formation, along, hidden;
    bool detected = false, unexplained = false;
    std::string accepted;     // effects the explainer accepted ("" for none)
    std::string stand_ins;    // effects refused, and why in short
    std::string discrepancy;  // its held-out improvement and what it depends on
    std::string unseen;       // the fitted physics replayed on an unseen flight of the case ("–": none carried)
    bool pass = false;
    std::string why;
    double seconds = 0;
};

struct UnnamedResult {
    std::vector<UnnamedRow> rows;
    int null_clean = 0, null_total = 0;
    bool pass = false;
    std::string table_path;
};

inline constexpr const char* kUnnamedTableFile = "unnamed.md";
std::string unnamed_case_list();
UnnamedResult run_unnamed(const UnnamedOptions& o);

}  // namespace dw::analysis
