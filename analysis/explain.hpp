#pragma once
// The mismatch explainer: resimulate a recorded flight through the physics, form residuals per axis,
// locate where they exceed the noise, fit each candidate effect with Ceres (robust loss) on
// training legs and score it on held-out legs (blocked cross-validation by leg) and by BIC,
// select effects forward, and report what was found (report.json per ../shared/FLIGHT_FORMAT.md,
// Markdown, PNG maps) with the fitted physics written beside it.
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "analysis/effects.hpp"
#include "analysis/noise.hpp"
#include "analysis/resimulation.hpp"
#include "analysis/spectrum.hpp"
#include "analysis/splits.hpp"
#include "core/numbers.hpp"
#include "flight/blocks.hpp"
#include "flight/flight.hpp"
#include "physics/config.hpp"

namespace dw::analysis {

using flight::AxisValues;

// Null flights (noise and turbulence only, 10 seeds) give 0.99-1.04: docs/EXPLAINER.md.
inline constexpr double kDetectExcess = 1.2;

struct ExplainOptions {
    physics::PhysicsConfig physics;  // the simulation the recording is compared with
    std::vector<Effect> candidates = all_effects();
    int folds = 5;                 // blocked cross-validation: leg % folds
    double max_delta_bic = -10.0;  // a candidate goes to the held-out test only below this ΔBIC (whole flight)
    double min_t = 3.0;            // held-out improvement: z over 0.25 s pieces of held-out blocks, best axis
    double min_gain = 0.05;        // ... and at least this fraction of that axis's error
    double region_z = 5.0;         // a region is reported above this |z|
    // A mismatch is detected, whatever its shape, when on some axis the residual's RMS over the
    // blocks exceeds this many noise floors (null flights: noise and turbulence alone, see
    // docs/EXPLAINER.md); it is then located with the weaker weak_region_z.
    double detect_excess = kDetectExcess;
    double weak_region_z = 3.0;
    int max_effects = 3;
    double huber_delta = 3.0;         // noise floors: a larger residual counts linearly in the fits
    double shift_half_width_s = 0.3;  // the located clock shifts are searched within ± this ...
    double shift_step_s = 0.005;      // ... in steps of this, refined by a parabola through the best
    std::uint64_t seed = 1;           // (the fits are deterministic; kept for the report)
    std::function<void(const std::string&)> progress;
    std::stop_token stop;  // checked between fits: dw::Stopped
};

// Throws dw::InputError naming the first option outside its range (each range below).
void validate(const ExplainOptions& o);
inline constexpr Range kFoldsRange{2, 50, "folds"};
inline constexpr Range kDeltaBicRange{-1e6, 0, ""};
inline constexpr Range kZRange{0, 1e3, ""};
inline constexpr Range kGainRange{0, 1, ""};
inline constexpr Range kExcessRange{1, 1e3, "noise floors"};
inline constexpr Range kMaxEffectsRange{1, 20, "effects"};
inline constexpr Range kHuberRange{0.5, 100, "noise floors"};
inline constexpr Range kShiftHalfWidthRange{0.01, 5, "s"};
inline constexpr Range kShiftStepRange{1e-4, 0.1, "s"};

struct Region {
    std::string axis;
    std::string where;
    double mean_residual = 0;
    double z = 0;
    // For the maps: the band and cell.
    double altitude_lo = 0, altitude_hi = 0;
    int direction = 0;
};

struct Shift {          // the time shift that best aligns recording and simulation in a group
    int direction = 0;  // +1: +E legs, -1: -E legs
    std::string band;   // vertical separation band
    double separation_m = 0;
    double shift_s = 0;
    std::size_t samples = 0;
};

// An accepted effect refused by the arbiter (analysis/arbiter.hpp): on the axis where it fell short,
// the fractions of the held-out error (weighed by the noise) that the model with it removes, that a
// discrepancy learnt without any effect removes, and that the model with a discrepancy on top removes.
struct ShortOfDiscrepancy {
    int axis = 2;
    double effect_gain = 0, discrepancy_gain = 0, together_gain = 0;
    double z = 0;  // the evidence that the effect adds to the discrepancy (held-out pieces)
};

struct CandidateResult {
    Effect effect;
    std::vector<double> values, lo, hi;  // estimates and 95 % intervals
    AxisValues heldout_before{}, heldout_after{};
    double delta_bic = 0;
    double t = 0;  // held-out z over pieces, best axis: the larger of signed ranks and Σd/√Σd²
    int best_axis = 2;
    double gain = 0;  // fraction of that axis's held-out MSE removed
    // Per axis: its held-out z and the fraction removed (on the pieces where it moves the prediction).
    AxisValues axis_t{}, axis_gain{};
    double total_ratio = 1;  // held-out error after / before, all axes (normalised)
    bool accepted = false;
    bool stand_in = false;  // it passed the held-out test, but its value changes across the flight
    // The one-value check (analysis/splits.hpp), when it was made: the axis it moves along most.
    std::optional<SplitMove> one_value;
    // Its largest z over the axes and parameters (the difference between the parts over its spread).
    std::optional<double> stand_in_z;
    // The held-out pieces that carry the best axis's evidence, counted by weight: (Σ|d|)² / Σd². The
    // sum over pieces cannot exceed its square root, whatever the data.
    double evidence_pieces = 0;
    bool too_few_pieces = false;                 // passes every test but the held-out z, which this flight cannot carry
    std::string note;                            // why (not) accepted
    int round = 0;                               // forward-selection round it was scored in
    std::map<int, double> heldout_pieces;        // per held-out piece: normalised squared error after, all axes
    std::vector<std::string> indistinguishable;  // accepted alternatives the held-out data cannot tell from it
    // Members of its family (EffectType::family) scored in its round, accepted or not, that the
    // held-out data cannot tell from it.
    std::vector<std::string> family_alike;
    // Members of its family that passed the held-out test in its round on their own, fitting less well.
    std::vector<std::string> family_passed;
    std::optional<ShortOfDiscrepancy> short_of;  // refused by the arbiter: it leaves structure the discrepancy models
};

// A family of effects the flight cannot separate, named together with what its members share: the
// located time shift for the delay family (the median of the shift table, weighted by samples).
struct FamilyVerdict {
    const physics::EffectFamily* family = nullptr;
    std::vector<std::string> members;  // the accepted one first
    double shared_value = 0;           // the delay family: seconds; the push family: × the single jets' sum
    std::string sentence;
};

// What the accepted effects leave, learnt as a function of the geometry, the predicted push, time,
// the direction of travel and the force's rate of change (analysis/discrepancy.hpp).
struct Discrepancy {
    bool fitted = false;     // false: too few samples for its inputs (note says why)
    std::size_t inputs = 0;  // regressors per axis
    AxisValues heldout_before{},
        heldout_after{};               // the final model's residual RMS on the held-out samples, without and with it
    AxisValues axis_t{}, axis_gain{};  // per axis: held-out z and fraction of the error removed
    double t = 0;                      // held-out z over pieces, best axis
    int best_axis = 2;
    double gain = 0;           // fraction of that axis's held-out error removed
    bool significant = false;  // t >= min_t and gain >= min_gain, as for a candidate
    bool significant_on(std::size_t a, double min_t, double min_gain) const {
        return axis_t[a] >= min_t && axis_gain[a] >= min_gain;
    }
    // What it depends on, when significant: each group of inputs' own share of the held-out gain on
    // the best axis (the gain lost without it), largest first, and the largest's words.
    std::vector<std::pair<std::string, double>> shares;
    std::string depends_on, sentence;
    // Detection by structure: per group of inputs, the evidence over held-out pieces that it adds to
    // the others (the nested test on the best axis: the discrepancy without the group against the
    // whole). `structured`: some group adds beyond what any group adds on null flights
    // (analysis/discrepancy.hpp, kStructureZ) and removes min_gain of the error on its own.
    std::vector<std::pair<std::string, double>> group_z;
    bool structured = false;
    std::string structured_by;
    std::string note;
};

// The held-out mean square of one axis's residual, shared out (issue 71): the noise floor's, the
// noise model's terms that grow with the push (physics/prediction_noise.hpp: the calibrated push
// share and timing spread, else 2 I p; and the lateral buffeting, at the final model's push), what
// the accepted effects remove, what the learnt discrepancy removes, and the rest — unexplained.
// Fractions that add to 1. A flight is explained to the noise when what the accepted effects leave
// is within kDetectExcess² of that noise (the excess a null flight shows) and the learnt
// discrepancy predicts none of it held out; modelled to the noise when the learnt discrepancy
// (not physics) predicts some of it and brings it there.
struct VarianceShares {
    int axis = 2;
    double total = 0;  // the mean square before the effects (N² or N²·m²)
    double noise = 0, turbulence = 0, effects = 0, discrepancy = 0, unexplained = 0;
    bool to_the_noise = false, modelled_to_the_noise = false;
};

struct ExplainResult {
    bool detected = false;
    AxisValues noise_floor{};
    FloorBasis noise_floor_basis = FloorBasis::far_samples;
    std::vector<Region> regions;  // strongest first
    std::vector<Shift> shifts;
    std::vector<CandidateResult> candidates;  // every score, every round
    std::vector<CandidateResult> accepted;    // strongest first, final parameters
    bool unexplained = false;
    AxisValues excess_before{}, excess_after{};  // residual RMS over the blocks / noise floor (0: axis not measured)
    AxisValues heldout_before{}, heldout_after{};
    physics::PhysicsConfig fitted;
    std::string formation;
    std::size_t samples = 0, legs = 0;                   // samples in blocks, blocks holding samples
    flight::BlockKind blocks = flight::BlockKind::legs;  // what the cross-validation blocks are
    double seconds = 0;
    std::size_t resimulations = 0;        // predictions of the whole flight the fits paid for (analysis/fit.hpp)
    Discrepancy discrepancy;              // what is left after the accepted effects, learnt
    std::vector<FamilyVerdict> families;  // accepted effects the flight cannot tell from their family
    OneJetPart one_jet;                   // where one jet pushes alone (a flight with two neighbours or more)
    // The strongest line in the residual's spectrum before the fit and after it (analysis/spectrum.hpp).
    SpectralLine line_before, line_after;
    VarianceShares shares;
    std::vector<BandTurbulence> turbulence;  // on the shares' axis, after the final model
};

ExplainResult explain(const flight::Flight& f, const ExplainOptions& o);

// The verdict in a line: "explained by: a, b" (with the families' sentences, and whether a residual
// remains) / "mismatch found, not explained" / "no mismatch".
std::string verdict_line(const ExplainResult& r);

// The report's lines on the noise: the held-out variance shared out; the turbulence the residual
// shows per band against the physics' intensity ("" where no band is measured).
std::string shares_line(const VarianceShares& v);
std::string turbulence_line(const ExplainResult& r, double physics_intensity);

// report.json, report.md, physics.yaml and the PNG figures into dir.
void write_report(const flight::Flight& f, const ExplainResult& r, const ExplainOptions& o, const std::string& dir);

}  // namespace dw::analysis
