#pragma once
// A learnt discrepancy (Kennedy & O'Hagan 2001; FLIGHT_FORMAT.md: "a learnt discrepancy: what
// remains after the accepted effects, modelled as a function of the geometry, with its held-out
// figures"). What the accepted effects leave is regressed, per axis, on smooth functions of where
// the neighbours are — Gaussian bumps over each neighbour's horizontal offset and height above the
// sufferer, summed over the neighbours, also times the offset's direction (a lateral push points
// along it) — with a constant and the sufferer's own velocity and acceleration (zero on a stand:
// a flying sufferer's force estimate m a − thrust errs with its own motion), and a slow drift. Ridge regression,
// fitted on each fold's training blocks and judged on its held-out blocks by the candidates' rule
// (the same pieces, the same z and gain).
//
// It names no physics: it says how much of what is left is a repeatable function of these inputs —
// what a missing effect would be, or a lab's own systematic error — and how much is not (noise, or
// what those inputs do not see), and which group of inputs carries it. It is the yardstick a named
// effect must meet (analysis/arbiter.hpp).
#include <array>
#include <map>
#include <string>
#include <vector>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"
#include "analysis/score.hpp"

namespace dw::analysis {

// The bumps: over the horizontal offset from 0 to the neighbour's near radius, kOffsetBumps of
// them evenly (each one spacing wide: about a jet's half-width at these separations), and over the height above at kHeightBumps points spread evenly between the near samples'
// 5th and 95th percentiles (each one spacing wide, at least kMinHeightWidth_m).
inline constexpr int kOffsetBumps = 9;
inline constexpr int kHeightBumps = 4;
inline constexpr double kMinHeightWidth_m = 0.05;
// A slow drift of the residual over the flight (a thrust map's error as the battery drains, a
// zero that wanders): bumps over time this far apart and this wide.
inline constexpr double kDriftSpacing_s = 4.0;
// The ridge penalties tried, relative to the mean diagonal of the (standardised) normal matrix;
// each axis takes the one that predicts held-out blocks best within each fold's training blocks.
inline constexpr std::array<double, 6> kRidgeGrid{1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0};

// Besides the geometry, what the splits of analysis/splits.hpp name, as functions of the model's own
// prediction p (per axis): p itself (a gain or a leak), p times powers of how hard the air pushes
// (x: the predicted wrench's norm in noise floors over its near samples' kPushQuantile; x and x²:
// a gain that changes with the push), p times powers of the flight's time (τ from −1 to 1 over the
// flight; τ and τ²: a gain that creeps), p's rate of change (a delay or a lag), p times the
// direction of travel, and p times how much of the push several jets share (SampleInfo::shared).
inline constexpr int kPushPowers = 2;
inline constexpr int kGainDriftPowers = 2;
inline constexpr double kPushQuantile = 0.95;

// The groups of inputs, each with what it means when the discrepancy depends on it most (one list:
// the columns are laid out in this order; the report's words come from here).
enum class InputGroup { constant, geometry, own_motion, drift, gain, push, rate, direction, sharing };
struct InputGroupInfo {
    InputGroup group;
    const char* name;
    const char* sentence;
};
inline constexpr std::array<InputGroupInfo, 9> kInputGroups{{
    {InputGroup::constant, "constant", "a constant offset"},
    {InputGroup::geometry, "geometry",
     "depends on where the neighbours are (their horizontal offset and height above): the jet's shape or where "
     "its wake goes (e.g. wakes that move sideways as they fall)"},
    {InputGroup::own_motion, "own motion", "follows the sufferer's own velocity and acceleration"},
    {InputGroup::drift, "time",
     "changes over the flight: a drift (a zero or a gain that creeps while the flight goes on)"},
    {InputGroup::gain, "gain", "is proportional to the force: a gain or a leak between axes"},
    {InputGroup::push, "push",
     "grows with the push, not in proportion to it: a gain that changes with the force (e.g. a sensor that stops "
     "following large forces)"},
    {InputGroup::rate, "rate of change", "follows how fast the force changes: a delay or a lag between force and pose"},
    {InputGroup::direction, "direction of travel", "changes with the neighbours' direction of travel"},
    {InputGroup::sharing, "shared push",
     "grows where several jets share the push: the jets combine otherwise than by adding their pushes (e.g. their "
     "velocities add before the drag)"},
}};

// Detection by structure. A discrepancy that removes a share of the held-out error is not yet a
// mismatch: every simulated flight carries some structure the resimulation does not have (the
// chips' sample-and-hold approximated by one delay, the turbulence's mean bias), spread thinly over
// many inputs, none of which adds to the others. A mismatch with a shape — one that changes with the
// direction of travel, the time, the push — sits in one group of inputs, which then adds to all the
// others: its nested held-out z (the discrepancy without the group against the whole, piece by
// piece, on the best axis) beyond kStructureZ, with min_gain of the error removed by it alone. The
// level is a normal tail of kStructureAlpha over the groups tested (Bonferroni); null flights stay
// clean (docs/EXPLAINER.md has their values).
inline constexpr double kStructureAlpha = 0.015;

// How the report names it.
inline constexpr const char* kDiscrepancyModel =
    "ridge regression, per axis, on Gaussian bumps over each neighbour's horizontal offset and height above the "
    "sufferer (summed over the neighbours, also times the offset's direction), a constant, the sufferer's own "
    "velocity and acceleration, bumps over the flight's time (a slow drift), and the model's own prediction: "
    "itself, times powers of the push and of time, times the direction of travel, times how much of the push "
    "several jets share, and its rate of change";

// Per held-out piece (analysis/score.hpp's pieces): squared residuals in noise floors, without and
// with the discrepancy, and the samples counted. Each sample is weighed by its noise — the floor and
// the turbulence that grows with the predicted push, 1 / (1 + (2 I |p| / σ)²) — in the fit and here.
struct PieceErrors {
    std::map<int, AxisValues> before, after;
    std::map<int, std::size_t> n;
};
// The sum over pieces on axis a (of PieceErrors::before or ::after).
double total(const std::map<int, AxisValues>& pieces, std::size_t a);

// Fills ExplainResult::discrepancy from the model's prediction `pred` (with what it depends on when
// `explain_dependence` and it is significant); its per-piece errors into `pieces` when given. The
// samples' noise weights follow `weigh_by`'s push (default: pred's).
struct DiscrepancyRun {
    bool explain_dependence = true;
    std::vector<InputGroup> without;  // groups of inputs left out (the arbiter's yardsticks)
    PieceErrors* pieces = nullptr;
    const std::vector<Wrench6>* weigh_by = nullptr;
    physics::LearntDiscrepancy* model = nullptr;  // given: the discrepancy fitted on every block, to carry
};
Discrepancy learn_discrepancy(const ExplainData& d, const std::vector<Wrench6>& pred, const Folds& folds,
                              const ExplainOptions& o, const DiscrepancyRun& run = {});

// A learnt discrepancy's correction at every wrench stamp of a flight (resimulated as `sim`, its
// samples described as `info`) whose model predicts `pred` there. Throws dw::InputError when m's
// inputs are not this build's.
std::vector<Wrench6> discrepancy_at(const physics::LearntDiscrepancy& m, const Resimulation& sim,
                                    const std::vector<SampleInfo>& info, const std::vector<Wrench6>& pred);

}  // namespace dw::analysis
