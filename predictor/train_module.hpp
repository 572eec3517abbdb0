#pragma once
// The seam between the predictor and its libtorch training (train_torch.cpp), which is built as a
// module of its own (libdw_torch_train.so, beside the executables) and loaded by train_model() the
// first time a model is trained: libtorch takes about 0.5 s of CPU to load, which every start of
// dw-predictor paid (its option errors, --help, the online node) when it was linked in.
#include "predictor/train.hpp"

namespace dw::predictor {

using TrainFunction = TrainResult (*)(const Dataset& train, const Dataset& validation, const TrainOptions& o,
                                      const LearntModel* baseline);
// The module's file name, in the executable's folder.
inline constexpr const char* kTrainingModule = "libdw_torch_train.so";
// Its entry point: returns the training function (a C name, so dlsym finds it unmangled).
inline constexpr const char* kTrainingEntry = "dw_training_entry";
using TrainingEntry = TrainFunction (*)();

}  // namespace dw::predictor
