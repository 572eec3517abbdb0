#pragma once
// Datasets for the force models, from flight folders (downwash-flight/1) or MCAP recordings.
// Each sample is one wrench row: the sufferer's wrench (the label) and every neighbour's state
// relative to the sufferer at the wrench's time — x_j - x_i, position and velocity, NED — taken
// from the 180 Hz poses by interpolation. Samples carry their leg so splits are by leg (80 Hz
// samples are autocorrelated; random splits leak), never by random sample.
#include <array>
#include <span>
#include <string>
#include <vector>

#include "flight/flight.hpp"

namespace dw::predictor {

inline constexpr int kMaxNeighbours = 3;
inline constexpr int kStateSize = 6;  // dn de dd dvn dve dvd

using RelState = std::array<double, kStateSize>;
using Wrench6 = std::array<double, 6>;  // f_n f_e f_d m_roll m_pitch m_yaw

struct Sample {
    double t = 0;                                     // stand clock [s]
    int k = 0;                                        // neighbours present
    std::array<RelState, kMaxNeighbours> x{};         // the first k are valid
    Wrench6 y{};                                      // recorded wrench
    int leg = -1;                                     // -1: not on a measurement leg
    int leg_direction = 0;                            // +1 towards +E, -1 towards -E, 0 unknown
    int source = 0;                                   // index into Dataset::sources
    std::span<const RelState> neighbours() const { return {x.data(), static_cast<std::size_t>(k)}; }
    // Where the formation is relative to the sufferer: N and E of the neighbours' centroid, and
    // the height of the lowest neighbour above the sufferer (the formation's reference altitude:
    // a Stack flies its lower vehicle there; flat formations are the same either way).
    std::array<double, 3> reference() const;
};

struct Source {
    std::string name;        // the flight folder or recording
    std::string formation;   // meta.json formation (leader_follower3 when leader_follower has K = 3)
};

struct Dataset {
    std::vector<Source> sources;
    std::vector<Sample> samples;
    void append(const Dataset& other);
    // Samples whose leg satisfies pred(leg) (samples off legs are dropped).
    template <class Pred> Dataset legs_where(Pred pred) const {
        Dataset d;
        d.sources = sources;
        for (const auto& s : samples)
            if (s.leg >= 0 && pred(s.leg)) d.samples.push_back(s);
        return d;
    }
    Dataset with_formation(const std::string& formation) const;
    Dataset with_k(int k_min, int k_max) const;
};

// Blocked split by leg: leg % period == test_phase → test, == val_phase → validation, else train.
struct Split {
    Dataset train, validation, test;
};
Split split_by_leg(const Dataset& d, int period = 5, int test_phase = 0, int val_phase = 1);

struct DatasetOptions {
    double max_distance_m = 3.0;  // neighbours farther than this from the sufferer are left out
};

// Throws dw::InputError naming the file for a malformed flight folder.
Dataset from_flight(const flight::Flight& f, const std::string& name, const DatasetOptions& o = {});
// A flight folder directory, or an .mcap recording (converted through the recorder's export).
Dataset load_dataset(const std::string& path, const DatasetOptions& o = {});

}  // namespace dw::predictor
