#pragma once
// The explainer's proof: flights made by `dw-sim fly` with one effect (or two) hidden in the
// physics, explained with the plain physics, and checked — the right effect named, the true
// parameter inside the reported interval, the held-out error reduced; null flights (noise only)
// must name nothing in at least 9 of 10 seeds.
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

namespace dw::analysis {

struct ProofOptions {
    std::string out_dir;
    int null_seeds = 10;
    std::vector<std::string> cases;   // empty: all; an unknown name is a dw::InputError
    std::stop_token stop;             // between flights and fits: dw::Stopped
    std::function<void(const std::string&)> progress;
};

struct ProofRow {
    std::string name, formation, hidden, found, truth, fitted, rmse;
    bool pass = false;
    std::string why;
    double seconds = 0;
};

struct ProofResult {
    std::vector<ProofRow> rows;
    int null_clean = 0, null_total = 0;
    bool pass = false;
    std::string table_path;
};

ProofResult run_proof(const ProofOptions& o);

}  // namespace dw::analysis
