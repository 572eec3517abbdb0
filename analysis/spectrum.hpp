#pragma once
// Detection by structure in time: a periodic mismatch (a beat between rotors, a vibration that grows
// with the force) spreads over the whole flight at the noise level, so the RMS excess does not see
// it, but it stands out as one line in the residual's spectrum. The residual of each measured axis,
// in units of its noise (the floor and the turbulence that grows with the push), is transformed at
// frequencies from kMinLineHz to kMaxLineHz in steps of 1 / the flight's span (the samples' own
// stamps: the blocks need not be contiguous); each line's power is divided by the local level — the
// median power within ±kLocalHz over ln 2, so that a coloured residual is not taken for a line — and
// is then about exponential with mean 1 where there is no line. The strongest over every frequency
// and axis (M of them) has a false-alarm probability of about 1 − (1 − e^−x)^M; a line is reported
// when that is below kLineAlpha.
#include <cstddef>
#include <vector>

#include "analysis/fit.hpp"
#include "analysis/noise.hpp"

namespace dw::analysis {

inline constexpr double kMinLineHz = 1.0;  // below: the passes' own rhythm
inline constexpr double kMaxLineHz = 20.0;
inline constexpr double kLocalHz = 0.25;
inline constexpr double kLineAlpha = 1e-3;

struct SpectralLine {
    int axis = 2;
    double hz = 0;
    double ratio = 0;          // its power over the local level
    double false_alarm = 1;    // the chance of a line this strong anywhere in a residual without one
    std::size_t lines = 0;     // frequencies × axes searched
    bool significant = false;  // false_alarm < kLineAlpha
};

// The strongest line in the residual of push.pred(), each sample weighed by its noise (PushNoise).
SpectralLine strongest_line(const ExplainData& d, const PushNoise& push);

}  // namespace dw::analysis
