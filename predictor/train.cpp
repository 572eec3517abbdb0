// train_model(): loads the libtorch training module (train_module.hpp) the first time it is needed.
#include <dlfcn.h>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/subprocess.hpp"
#include "predictor/train_module.hpp"

namespace dw::predictor {

Structure structure_of(const std::string& kind) {
    if (kind == "naive_linear" || kind == "learnt_linear") return Structure::sum;
    if (kind == "deep_sets") return Structure::deep_sets;
    throw InputError(log::cat("model kind '", kind, "' (expected naive_linear, learnt_linear or deep_sets)"));
}

namespace {
// Throws dw::RuntimeError (an installation problem, exit 1) naming the module and dlopen's reason.
TrainFunction load_training() {
    const std::string path = executable_dir() + "/" + kTrainingModule;
    void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // kept for the process's life
    if (!module) throw RuntimeError(log::cat("cannot load the training module: ", ::dlerror()));
    auto* entry = reinterpret_cast<TrainingEntry>(::dlsym(module, kTrainingEntry));
    if (!entry) throw RuntimeError(log::cat("cannot load the training module: ", ::dlerror()));
    return entry();
}
}  // namespace

TrainResult train_model(const Dataset& train, const Dataset& validation, const TrainOptions& o,
                        const LearntModel* baseline) {
    static const TrainFunction train_function = load_training();  // once; tried again if it threw
    return train_function(train, validation, o, baseline);
}

}  // namespace dw::predictor
