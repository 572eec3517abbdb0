#pragma once
// How honest the explainer's 95 % intervals are (issue 15, item 6): flights flown by `dw-sim fly`
// with one effect hidden at a value drawn per seed, explained with that effect as the only
// candidate, and the interval of its fit checked against the hidden value. Every one-parameter
// effect of the vocabulary that a flight over the stand can show, and each component of a
// several-parameter one (the positions' offset). `dw-explain coverage` runs it; docs/EXPLAINER.md holds the table.
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

namespace dw::analysis {

// Below this, an interval is not honest: the verdict says so.
inline constexpr double kMinCoverage = 0.85;

struct CoverageOptions {
    std::string out_dir;
    int seeds = 20;                    // flights per effect
    std::vector<std::string> effects;  // empty: all; an unknown name is a dw::InputError
    int legs = 36;                     // legs per flight
    int jobs = 2;                      // flights flown and explained at once
    std::stop_token stop;
    std::function<void(const std::string&)> progress;
};

struct CoverageRow {
    std::string effect, param, formation, drawn;  // drawn: the range the hidden values come from
    int flights = 0;
    int intervals = 0;  // flights where the fit was worth an interval (ΔBIC < -10, not pinned)
    int covered = 0;    // ... and the interval holds the hidden value
    int accepted = 0;   // flights where the effect was accepted
    double mean_half_width = 0;
    enum class Verdict { honest, too_narrow, not_identifiable } verdict = Verdict::honest;
    std::string why;  // the verdict in words
    double coverage() const { return intervals > 0 ? static_cast<double>(covered) / intervals : 0.0; }
};

struct CoverageResult {
    std::vector<CoverageRow> rows;
    std::string table_path;
    bool pass = false;  // every row at >= kMinCoverage or said to be not identifiable
};

// The coverage run's table, in its output folder.
inline constexpr const char* kCoverageTableFile = "coverage.md";
CoverageResult run_coverage(const CoverageOptions& o);

}  // namespace dw::analysis
