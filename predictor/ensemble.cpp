#include "predictor/ensemble.hpp"

#include <algorithm>
#include <future>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/log.hpp"

namespace dw::predictor {

namespace {

// The first member's metadata with each member's (seed, epochs, validation loss) listed.
std::string with_members(const std::vector<TrainResult>& members) {
    auto j = nlohmann::json::parse(members.front().model.metadata_json);
    auto& list = j["members"] = nlohmann::json::array();
    for (const auto& r : members) list.push_back(nlohmann::json::parse(r.model.metadata_json));
    return j.dump();
}

}  // namespace

int members_for(const std::string& kind, int members) {
    return structure_of(kind) == Structure::deep_sets ? members : 1;
}

TrainResult train_members(const Dataset& train, const Dataset& validation, const TrainOptions& o, int members,
                          const LearntModel* baseline, const std::function<void(const std::string&)>& say) {
    members = members_for(o.kind, members);
    auto train_one = [&](int member) {
        TrainOptions t = o;
        t.seed = o.seed + static_cast<std::uint64_t>(member) * kMemberSeedStride;
        const std::string name = members > 1 ? log::cat(o.kind, " ", member + 1, "/", members) : o.kind;
        // The one progress line of trainings given `say` (o.progress cannot tell members apart).
        if (say && (members > 1 || !o.progress))
            t.progress = [&say, name](int epoch, double tl, double vl) {
                if (epoch % kProgressEveryEpochs == 0)
                    say(log::cat("  ", name, " epoch ", epoch, ": training ", tl, ", validation ", vl));
            };
        auto r = train_model(train, validation, t, baseline);
        if (say) say(log::cat("  ", name, ": ", r.epochs, " epochs (best ", r.best_epoch, "), ", r.seconds, " s"));
        return r;
    };
    // Members train at once, each seeded as if alone (train_model draws its weights under a lock).
    std::vector<std::future<TrainResult>> running;
    for (int m = 1; m < members; ++m) running.push_back(std::async(std::launch::async, train_one, m));
    std::vector<TrainResult> done{train_one(0)};
    for (auto& f : running) done.push_back(f.get());
    if (members == 1) return std::move(done.front());

    TrainResult r;
    std::vector<LearntModel> models;
    for (const auto& m : done) {
        models.push_back(m.model);
        r.epochs = std::max(r.epochs, m.epochs);
        r.best_epoch = std::max(r.best_epoch, m.best_epoch);
        r.seconds = std::max(r.seconds, m.seconds);
        r.best_validation_loss += m.best_validation_loss / static_cast<double>(members);
    }
    r.model = average_of(models);
    r.model.metadata_json = with_members(done);
    return r;
}

}  // namespace dw::predictor
