#pragma once
// Deep Sets trained several times, each from its own seed, and averaged into one model
// (average_of, model.hpp): one training's spread where jets merge is as large as what separates two
// variants of the model (docs/PREDICTOR.md), and the average of a few is steadier than any of them.
#include <functional>
#include <string>

#include "predictor/dataset.hpp"
#include "predictor/model.hpp"
#include "predictor/train.hpp"

namespace dw::predictor {

inline constexpr int kProgressEveryEpochs = 10;  // a training's progress line every this many epochs

// How many trainings a model of `kind` averages when `members` are asked for: Deep Sets only.
int members_for(const std::string& kind, int members);

// A deep_sets model: `members` trainings at once (member i from seed o.seed + i * kMemberSeedStride,
// each with o.threads), averaged; its metadata lists every member's. The result's epochs, best epoch
// and seconds are the members' largest, its validation loss their mean. Any other kind, or one
// member: one training, as train_model. `say` gets one line per training when it ends, and one every
// kProgressEveryEpochs epochs naming the training, unless o.progress is set and there is one
// training (o.progress then gets every epoch). Throws as train_model.
TrainResult train_members(const Dataset& train, const Dataset& validation, const TrainOptions& o, int members,
                          const LearntModel* baseline = nullptr,
                          const std::function<void(const std::string&)>& say = {});

}  // namespace dw::predictor
