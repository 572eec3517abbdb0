#pragma once
// One value along every axis the flight spans. An effect of the vocabulary is one value for the
// whole flight — a clock offset, a gain, a lag — so, fitted again on parts of the flight split
// along each axis it spans (time, the predicted push, the neighbours' height and horizontal
// separation, the direction of travel, how much of the push several jets share), it must take
// the same value in every part. An effect
// standing in for something the vocabulary does not name (a drift, a sensor that stops following
// large forces, wakes that move sideways as they fall) takes values that move along one of them.
//
// The test, per axis and parameter: the near samples' lowest and highest thirds along the axis (or
// the two directions of travel), the effect refitted on each, their difference against its spread
// over kSplitGroups blocked jackknife groups (block % kSplitGroups; the covariance alone is several
// times too narrow on autocorrelated, turbulent data), as Student's t with groups − 1 degrees of
// freedom. The family-wise level kSplitAlpha is shared by every axis and parameter tested
// (Bonferroni), so that a flight with one value stays clean whatever the number of splits.
//
// The refits on the parts (and on the parts less each jackknife group) are Gauss-Newton steps from
// the whole flight's fit, with the whole fit's Huber weights: P + 1 resimulations per candidate for
// every split, instead of two full fits per part and group. The axis the effect moves along most is
// then fitted in full on its two parts for the report's words.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit.hpp"

namespace dw::analysis {

enum class SplitAxis { time, push, height, separation, direction, company };

struct SplitAxisInfo {
    SplitAxis axis;
    const char* name;        // in the report: "moves along <name>"
    const char *low, *high;  // the two parts in words
    bool ratio_rule;         // spanned only when the highest third's value is kSpanRatio × the lowest's
};

// The axes, in the order they are tested and reported.
inline constexpr std::array<SplitAxisInfo, 6> kSplitAxes{{
    {SplitAxis::time, "time", "early", "late", false},
    {SplitAxis::push, "predicted push", "where the push is weak", "where it is strong", true},
    {SplitAxis::height, "neighbour height", "on the lowest passes", "on the highest passes", true},
    {SplitAxis::separation, "horizontal separation", "close by", "farther out", true},
    {SplitAxis::direction, "direction of travel", "on -E legs", "on +E legs", false},
    // How the jets combine: a sum of single-neighbour pushes keeps one value whether one jet pushes or several share.
    {SplitAxis::company, "shared push", "where one jet pushes", "where several share the push", false},
}};

inline constexpr int kSplitGroups = 10;              // blocked jackknife groups: block % this
inline constexpr double kSplitAlpha = 0.015;         // family-wise, over every axis and parameter tested
inline constexpr std::size_t kMinPartSamples = 100;  // a part with fewer samples is not tested
inline constexpr double kSpanRatio = 1.5;            // a flight at one height cannot show a dependence on it
// The shared push (analysis/resimulation.hpp) is spanned only when its highest third reaches this:
// a second jet carries at least a fifth of the push there.
inline constexpr double kMinSharedSpan = 0.2;
// "One jet pushes alone": the other jets carry less than this share of the push. Jets that do not
// add as forces differ from the sum by far more than their share (velocities that add: a second jet
// with 1 % of the push makes it 20 % larger), so a flight's least shared third is not one jet.
inline constexpr double kOneJetShare = 0.01;
// The push is split among the near samples where the model predicts at least this push (noise
// floors, RMS over the axes): where it predicts none, no effect can be measured.
inline constexpr double kMeasurablePush = 1.0;

// Where one jet pushes alone: the near samples with a measurable push whose other jets carry less
// than kOneJetShare of it. A gain of the whole push is told from how jets combine only there
// (physics::kPushFamily).
struct OneJetPart {
    std::size_t measured = 0;  // near samples with a measurable push
    std::size_t alone = 0;     // of them, where one jet pushes alone
    double median_share = 0;   // the share the other jets carry, at the median of the measured
    bool enough() const { return alone >= kMinPartSamples; }
};
OneJetPart one_jet_part(const ExplainData& d, const std::vector<Wrench6>& with);

// The split along which the effect's value moves most (largest t), and whether beyond the threshold.
struct SplitMove {
    SplitAxis axis = SplitAxis::time;
    std::string param;
    double low = 0, high = 0;  // the parameter fitted on the two parts
    double z = 0;              // |difference| / jackknife spread
    double threshold = 0;      // the t the family-wise level allows here
    int tested = 0;            // axis × parameter tests made
    bool moved = false;        // z > threshold: not one value for the flight
    std::string note;          // in words
};

// The check for effect e at `values` on top of the model `current`. Empty when no axis could be
// tested (too few near samples, or the effect does not act on both parts of any axis).
std::optional<SplitMove> one_value_check(const ExplainData& d, const physics::PhysicsConfig& current, const Effect& e,
                                         const std::vector<double>& values, double factor);

const SplitAxisInfo& split_info(SplitAxis a);

}  // namespace dw::analysis
