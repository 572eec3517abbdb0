#pragma once
// Training the learnt models with libtorch: Adam on the mean squared error of the normalised
// wrench, mini-batches, early stopping on held-out validation legs, fixed seeds. The result is a
// LearntModel evaluated with Eigen (model.hpp). This header keeps libtorch out of its users.
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>

#include "core/numbers.hpp"
#include "core/parallel.hpp"
#include "predictor/dataset.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

inline constexpr Range kEpochsRange{1, 100000};
inline constexpr Range kHiddenRange{4, 4096};
inline constexpr Range kPatienceRange{1, 100000};
inline constexpr Range kThreadsRange{1, 64};
// libtorch's threads per training. One by default: the models are small, and two OpenMP threads
// spin against each other and against any other busy process on a 2-core machine (docs/BENCHMARKS.md).
inline constexpr int kDefaultTrainThreads = 1;

// Deep Sets trainings averaged into one model (average_of), each from its own seed: one training's
// spread on the merged jets is as large as what separates two variants (docs/PREDICTOR.md).
inline constexpr int kDefaultDeepSetsMembers = 2;
inline constexpr Range kMembersRange{1, 16};
inline constexpr std::uint64_t kMemberSeedStride = 1000;  // member i trains from seed + i * this

struct TrainOptions {
    std::string kind = "deep_sets";  // naive_linear, learnt_linear or deep_sets
    int hidden = 64;                 // width of the hidden layers
    int latent = 32;                 // deep sets: width of phi's output
    int max_epochs = 150;
    int patience = 15;  // epochs without a better validation loss before stopping
                        // (the step is halved after every patience/3 of them)
    double learning_rate = 2e-3;
    int batch = 256;
    std::uint64_t seed = 1;
    // A sum model that starts at zero (phi's last layer zeroed), that zero its score to beat: a
    // correction to a base model moves off the base only as far as the validation flights agree.
    bool from_zero = false;
    int threads = kDefaultTrainThreads;
    // When set, the training holds one of these for its time (each counts `threads` cores), taken at
    // once or when one is free (work that fills in: the study's generalisation).
    Cores* cores = nullptr;
    Cores::Turn turn = Cores::Turn::now;
    std::string split = "by leg";  // how the training and validation legs were chosen (metadata)
    // Called after every epoch: epoch, training loss, validation loss (normalised MSE).
    std::function<void(int, double, double)> progress;
    std::stop_token stop;  // checked every mini-batch: dw::Stopped, and nothing is returned
};

Structure structure_of(const std::string& kind);  // throws dw::InputError for an unknown kind

struct TrainResult {
    LearntModel model;
    int epochs = 0;
    int best_epoch = 0;
    double best_validation_loss = 0;
    double seconds = 0;
};

// Throws dw::InputError when there is nothing to train on. A deep_sets model given a sum model as
// `baseline` starts from exactly the baseline and learns the residual on it; the baseline's psi
// trains on with it (where jets merge, the residual takes the merging, and psi is freed of it).
TrainResult train_model(const Dataset& train, const Dataset& validation, const TrainOptions& o,
                        const LearntModel* baseline = nullptr);

}  // namespace dw::predictor
