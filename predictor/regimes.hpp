#pragma once
// The regime map: for each formation × altitude band, what kind of aggregate downwash the
// measured forces show on held-out legs (the D axis, where the downwash pushes):
//   chaotic     the signal is within the noise: no model (the sum or Deep Sets) explains even
//               min_explained of the measured f_d's mean square on the held-out legs;
//   non_linear  Deep Sets is significantly better than its own sum part (sum_to_compare):
//               paired z over held-out legs ≥ min_z and the squared error falls by ≥ min_gain;
//   linear      otherwise: the sum predicts as well as anything. A formation with one neighbour has
//               no aggregate: it is linear or chaotic, never non-linear.
// The sum compared is Deep Sets' own Σ psi, trained with it on the same data: what its set term
// adds is then the aggregate's nonlinearity alone — not a better single-neighbour model (learnt
// linear, fitted to flights where jets merge, is bent by them), nor a naive model's smaller
// training set. A Deep Sets model without a baseline is compared with learnt linear.
#include <stop_token>
#include <string>
#include <vector>

#include "core/numbers.hpp"
#include "predictor/dataset.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

enum class Regime { chaotic, linear, non_linear };
const char* regime_name(Regime r);

inline constexpr Range kMinZRange{0, 20};     // a z beyond 20 is never reached by a few hundred pieces
inline constexpr Range kFractionRange{0, 1};  // min_explained, min_gain

struct RegimeOptions {
    double band_m = 0.15;         // ± around each altitude the flights fly
    double min_explained = 0.25;  // of the mean square of f_d, by the better model (below: chaotic)
    double min_z = 3.0;           // Deep Sets better than the sum over held-out legs
    double min_gain = 0.10;       // and by at least this fraction of the sum's squared error
    double piece_s =
        0.25;  // held-out legs are compared in pieces of this length (the noise decorrelates within ~0.1 s)
};

struct RegimeRow {
    std::string formation;
    double altitude_m = 0;
    Regime regime = Regime::chaotic;
    std::size_t legs = 0;
    double signal_rms = 0;  // measured f_d [N]
    double explained = 0;   // 1 − best squared error / mean square of f_d
    double gain = 0;        // 1 − Deep Sets' squared error / the sum's
    double z = 0;           // paired z over pieces of held-out legs (the sum's minus Deep Sets' mean squared error)
};

// Every formation of `test` (held-out legs) at each altitude; bands with too few pieces of legs are
// left out. A stop requested through `stop` ends it with dw::Stopped.
// The sum model Deep Sets is compared with (above).
LearntModel sum_to_compare(const LearntModel& deep, const LearntModel& learnt_linear);

std::vector<RegimeRow> classify_regimes(const ForceModel& sum, const ForceModel& deep, const Dataset& test,
                                        const std::vector<double>& altitudes_m, const RegimeOptions& o = {},
                                        std::stop_token stop = {});

std::string regimes_markdown(const std::vector<RegimeRow>& rows, const RegimeOptions& o);
std::string regimes_csv(const std::vector<RegimeRow>& rows);
// One cell per formation × altitude, coloured by regime, with the gain and z written in it.
// Throws dw::RuntimeError if the PNG cannot be written.
void draw_regime_map(const std::vector<RegimeRow>& rows, const std::string& png);

}  // namespace dw::predictor
