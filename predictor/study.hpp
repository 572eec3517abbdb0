#pragma once
// The study in one call: simulate the flights (single-neighbour legs and every formation), write
// them as flight folders, read them back through the contract (no side channel), split by leg,
// train the naive linear, learnt linear and Deep Sets models, compare them with the physics on
// held-out legs (the Table 1 metric and RMSE), run the generalisation tests and draw the maps.
#include <cstdint>
#include <functional>
#include <memory>
#include <stop_token>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "physics/config.hpp"
#include "predictor/evaluate.hpp"
#include "predictor/regimes.hpp"
#include "predictor/train.hpp"

namespace dw::predictor {

struct StudyOptions {
    physics::PhysicsConfig physics;
    std::string out_dir;
    std::vector<std::string> formations{"single",           "side_by_side", "leader_follower",
                                        "leader_follower3", "stack",        "hybrid"};
    int legs = 90;                     // per flight: 30 lines a band, 0.067 m apart (the merged jets are narrow)
    double single_half_width_m = 1.6;  // the single-neighbour flights' square (others: 1 m)
    std::uint64_t seed = 1;
    int max_epochs = 150;
    int threads = kDefaultTrainThreads;  // libtorch's threads per training
    int jobs = machine_cores();          // cores it may use: flights flown at once, trainings (jobs / threads) at once
    int members = kDefaultDeepSetsMembers;
    bool generalisation = true;  // train on K <= 2, test on K = 3; leave stack out
    bool maps = true;
    ArenaOptions arena;
    std::function<void(const std::string&)> progress;  // one line per step
    std::stop_token stop;                              // flying, training and drawing stop with dw::Stopped
};

struct StudyResult {
    std::vector<ComparisonRow> table;           // held-out legs, every formation, every model
    std::vector<ComparisonRow> generalisation;  // models trained without the formation they are tested on
    // The same comparison at each altitude band the flights fly (0.3, 0.8, 1.3 m): the arena metric
    // at that altitude, RMSE over the held-out samples in the band.
    std::vector<std::pair<double, std::vector<ComparisonRow>>> by_altitude;
    std::vector<RegimeRow> regimes;  // each formation x altitude band: chaotic, linear or non-linear
    std::string markdown_path, csv_path;
};

StudyResult run_study(const StudyOptions& o);

// The regime map of a study's folder: its flights' held-out legs, its learnt linear and Deep Sets
// models; written beside them as regimes.md, regimes.csv and regimes.png. Throws dw::InputError
// naming what is missing for a folder that is not a study's.
struct RegimesFiles {
    std::vector<RegimeRow> rows;
    std::string markdown_path, csv_path, png_path;
};
RegimesFiles regimes_of_study(const std::string& study_dir, const RegimeOptions& o = {}, std::stop_token stop = {});
RegimesFiles write_regimes(const std::vector<RegimeRow>& rows, const std::string& dir, const RegimeOptions& o = {});

// Training one learnt model the way the study and the real-flight comparison do, saved to path.
struct TrainPlan {
    std::uint64_t seed = 1;
    int max_epochs = 150;
    int threads = kDefaultTrainThreads;
    int members = kDefaultDeepSetsMembers;  // deep_sets: trainings averaged (1: one training)
    bool from_zero = false;                 // a sum model starts at zero (TrainOptions::from_zero)
    Cores* cores = nullptr;                 // as TrainOptions
    Cores::Turn turn = Cores::Turn::now;
    std::string split;                                 // how the blocks were split (the model's metadata)
    std::function<void(const std::string&)> progress;  // one line per step
    std::stop_token stop;
};
// A deep_sets model is trained on `baseline` (a sum model; see train_model) when one is given.
std::unique_ptr<LearntModel> train_and_save(const std::string& kind, const Dataset& train, const Dataset& validation,
                                            const TrainPlan& plan, const std::string& path,
                                            const LearntModel* baseline = nullptr);

// The arena-metric value of `model` on `formation` and `axis` in a table (NaN if absent).
double table_value(const std::vector<ComparisonRow>& rows, const std::string& formation, const std::string& model,
                   int axis, bool arena = true);

}  // namespace dw::predictor
