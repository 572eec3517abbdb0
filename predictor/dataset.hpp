#pragma once
// Datasets for the force models, from flight folders (downwash-flight/1) or MCAP recordings.
// Each sample is one wrench row: the sufferer's wrench (the label) and every neighbour's state
// relative to the sufferer at the wrench's time — x_j - x_i, position and velocity, NED — taken
// from the 180 Hz poses by interpolation. Samples carry their block — a measurement leg, or in a
// flight without legs an encounter (each pass of a neighbour near the sufferer) or a stretch of
// time (flight::find_blocks) — so splits are by block (samples are autocorrelated; random splits
// leak), never by random sample.
#include <array>
#include <limits>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "flight/blocks.hpp"
#include "flight/flight.hpp"
#include "physics/config.hpp"

namespace dw::predictor {

inline constexpr int kMaxNeighbours = 3;
inline constexpr int kStateSize = 6;  // dn de dd dvn dve dvd

using RelState = std::array<double, kStateSize>;
using flight::kFdAxis;
using flight::Wrench6;

// No prediction: a model that cannot say anything about a sample (the reference where a flight has none).
inline constexpr Wrench6 kNoPrediction{
    std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
    std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
    std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};

struct Sample {
    double t = 0;                                    // stand clock [s]
    int k = 0;                                       // neighbours present
    std::array<RelState, kMaxNeighbours> x{};        // the first k are valid
    Wrench6 y{};                                     // recorded wrench
    int leg = -1;                                    // the block (leg, encounter, time); -1: none
    int leg_direction = 0;                           // +1 towards +E, -1 towards -E, 0 unknown (or not on legs)
    int source = 0;                                  // index into Dataset::sources
    std::array<std::uint8_t, kMaxNeighbours> who{};  // which of the source's neighbours x[j] is
    double height = 0;                               // the sufferer above the floor [m]
    Wrench6 recorded_prediction = kNoPrediction;     // the flight's reference.csv at t (NaN: none)
    std::span<const RelState> neighbours() const { return {x.data(), static_cast<std::size_t>(k)}; }
    // Where the formation is relative to the sufferer: N and E of the neighbours' centroid, and
    // the height of the lowest neighbour above the sufferer (the formation's reference altitude:
    // a Stack flies its lower vehicle there; flat formations are the same either way).
    std::array<double, 3> reference() const;
};

struct Source {
    std::string name;       // the flight folder or recording
    std::string formation;  // meta.json formation (leader_follower3 when leader_follower has K = 3)
    // Each body's parameters as the flight gives them (meta.json), for the physics per body.
    physics::VehicleParams sufferer;
    std::vector<physics::VehicleParams> neighbours;                    // meta.json's neighbours, in order
    bool flying = false;                                               // no load stand: the sufferer's height varies
    std::array<bool, 6> measured{true, true, true, true, true, true};  // columns carrying a measurement
    flight::BlockKind blocks = flight::BlockKind::legs;
    std::string reference;         // what reference.csv's model is (meta.json), "" when the flight has none
    bool estimated_poses = false;  // meta.json pose_source: estimate (the vehicles' own estimates, not motion capture)
};

struct Dataset {
    std::vector<Source> sources;
    std::vector<Sample> samples;
    void append(const Dataset& other);
    // Samples whose leg satisfies pred(leg) (samples off legs are dropped).
    template <class Pred>
    Dataset legs_where(Pred pred) const {
        Dataset d;
        d.sources = sources;
        for (const auto& s : samples)
            if (s.leg >= 0 && pred(s.leg)) d.samples.push_back(s);
        return d;
    }
    Dataset with_formation(const std::string& formation) const;
    // Samples of the flights that carry a reference prediction (reference.csv).
    Dataset with_reference() const;
    Dataset with_k(int k_min, int k_max) const;
    // Samples with a neighbour whose reference altitude is within ± band_m of altitude_m.
    Dataset in_altitude_band(double altitude_m, double band_m) const;
    // Samples of flights with exactly one neighbour (the naive linear model's training data).
    Dataset from_two_vehicle_flights() const;
};

// Blocked split by leg: leg % period == test_phase → test, == val_phase → validation, else train.
struct Split {
    Dataset train, validation, test;
};
inline constexpr int kSplitPeriod = 5;  // block % 5 == 0: held out for testing, == 1: validation
Split split_by_leg(const Dataset& d, int period = kSplitPeriod, int test_phase = 0, int val_phase = 1);

struct DatasetOptions {
    double max_distance_m = 3.0;     // neighbours farther than this from the sufferer are left out
    physics::PhysicsConfig physics;  // a body meta.json does not describe takes these parameters
};

// Throws dw::InputError naming the file for a malformed flight folder.
Dataset from_flight(const flight::Flight& f, const std::string& name, const DatasetOptions& o = {});
// A flight folder directory, or an .mcap recording (converted through the recorder's export).
Dataset load_dataset(const std::string& path, const DatasetOptions& o = {});

}  // namespace dw::predictor
