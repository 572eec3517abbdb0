#pragma once
// The force models on recorded flights (another lab's, or the lab's own without legs): read the
// flight folders, split by block (encounters in flights without legs; block % 5 == 0 held out,
// == 1 validation), train the naive linear model on two-vehicle flights only and the learnt linear
// and Deep Sets models on all, compare them with the physics (each vehicle with its own
// parameters) on the held-out blocks — RMSE per axis and peak f_d error per block — and draw f_d
// against the nearest neighbour's position relative to the sufferer, recorded beside each model.
// The same two models are also trained on what the physics leaves (physics+…): each correction
// starts at none and is shrunk, axis by axis, by the validation samples (shrink_to in real.cpp).
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

#include "physics/config.hpp"
#include "predictor/evaluate.hpp"
#include "predictor/train.hpp"

namespace dw::predictor {

struct RealOptions {
    std::vector<std::string> data;  // flight folders or .mcap recordings
    // Trials never seen in training (leave-trials-out): every block of these flights is held out;
    // of the others, one whole flight per vehicle mix flown twice or more validates and the rest
    // train (when no mix is flown twice: every block trains but block % 5 == 1, which validates).
    // Empty: block % 5 == 0 of every flight held out.
    std::vector<std::string> unseen;
    physics::PhysicsConfig physics;  // the physics model, and parameters for bodies a flight does not describe
    std::string out_dir;
    std::uint64_t seed = 1;
    int max_epochs = 150;
    int threads = kDefaultTrainThreads;     // libtorch's threads per training
    int members = kDefaultDeepSetsMembers;  // Deep Sets trainings averaged
    std::function<void(const std::string&)> progress;
    std::stop_token stop;
};

struct RealResult {
    std::vector<ComparisonRow> table;
    std::size_t train = 0, validation = 0, test = 0;  // samples
    bool naive = false;                               // trained (the data held a two-vehicle flight)
    std::string markdown_path, csv_path, map_path;
};

// Throws dw::InputError (exit 2) saying why when a split ends with no samples.
RealResult run_real(const RealOptions& o);

}  // namespace dw::predictor
