#pragma once
// A flight's bodies as tracks in time, and its cross-validation blocks: the legs it was flown on
// (legs.csv, or found from the neighbours' motion), its encounters, or stretches of time. Read
// by the explainer's resimulation and the predictor's datasets (body_tracks, BlockCursor); the
// folder's files are flight.hpp's.
#include <array>
#include <string>
#include <vector>

#include "flight/flight.hpp"

namespace dw::flight {

// Per-body pose tracks, for lookup by time.
struct Track {
    std::vector<double> t;
    std::vector<std::array<double, 3>> p;
    std::vector<std::array<double, 4>> q;
    // Linear interpolation (clamped at the ends) of the position at time t.
    std::array<double, 3> position_at(double time) const;
    // Central difference of the interpolated position over ±half_window_s (±20 ms spans several
    // 180 Hz poses, so mocap noise is not differentiated sample by sample).
    std::array<double, 3> velocity_at(double time, double half_window_s = 0.02) const;
};
std::vector<Track> tracks(const Flight& flight);  // indexed like Flight::bodies

// The flight's sufferer and its neighbours (in meta.json's order) as tracks: the one per-sample
// view the predictor's datasets and the explainer's resimulation read. Throws InputError (prefixed
// with `where`, e.g. the flight's folder) when the sufferer has no poses or a neighbour fewer than
// two (a velocity needs two).
struct BodyTracks {
    Track sufferer;
    std::vector<Track> neighbours;
};
BodyTracks body_tracks(const Flight& flight, const std::string& where = "");

// Finds measurement legs in a flight without legs.csv: stretches where the neighbours' centroid
// moves horizontally at a steady speed (> 0.25 m/s) for at least 2 s.
std::vector<Leg> find_legs(const Flight& f);

// Cross-validation blocks. A flight flown on straight legs uses its legs. A flight without them
// (a swap, a random walk, another lab's log) is split by encounter: each pass of a neighbour
// within its encounter radius of the sufferer horizontally is one block, the flight cut halfway
// between successive closest approaches. Too few encounters: equal stretches of time.
enum class BlockKind { legs, encounters, time };
const char* to_string(BlockKind k);
struct Blocks {
    BlockKind kind = BlockKind::legs;
    std::vector<Leg> blocks;  // numbered from 0, in time order
};
inline constexpr double kTimeBlock_s = 4.0;  // the longest time block when splitting by time
// encounter_radius_m: per neighbour of meta.json, in its order.
Blocks find_blocks(const Flight& f, int min_blocks, const std::vector<double>& encounter_radius_m);

// Walks a flight's blocks forward in time: at(t) is the block holding t, or none. Times must not
// decrease between calls (one pass over a time-ordered series).
class BlockCursor {
public:
    explicit BlockCursor(const std::vector<Leg>& blocks) : blocks_(blocks) {}
    const Leg* at(double t);

private:
    const std::vector<Leg>& blocks_;
    std::size_t i_ = 0;
};

}  // namespace dw::flight
