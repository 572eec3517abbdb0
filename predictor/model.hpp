#pragma once
// Force models: given every neighbour's state relative to the sufferer, the wrench on it.
//   physics        the simulator's wrench model (the jets, the planform, the aggregation law)
//   naive_linear   Σ_j psi(x_j - x_i), psi trained on single-neighbour flights only
//   learnt_linear  the same sum structure, trained on multi-vehicle data
//   deep_sets      Phi(Σ_j phi(x_j - x_i))
// Learnt models are trained with libtorch (train.hpp) but evaluated here with Eigen, so serving
// a model needs no libtorch. A saved model (JSON, kModelFormat) carries its input
// normalisation and its metadata.
//
// Every learnt model sees a neighbour through the same features (features_of): the relative state
// and three numbers that carry the jet's own invariances (horizontal distance, the similarity
// variable horizontal distance / vertical separation, and 1 / vertical separation, the centreline
// decay), so a small network need not rediscover them from raw coordinates. A Deep Sets model may
// carry a sum model as its baseline (its psi, which trains on with it) and learn what the sum misses:
//   deep_sets with baseline   Σ_j psi(x_j - x_i) + Phi(Σ_j w_j phi(x_j - x_i)) - Phi(0), Phi's last layer starting at 0
// Deep Sets alone sees the set: each neighbour's features end with w_j (jet_overlap; 0 for a sum
// model). On a baseline it also weighs its term, so Deep Sets departs from its baseline only where
// two neighbours' jets overlap — never for one neighbour, nor low down, where jets are narrow.
#include <array>
#include <cmath>
#include <Eigen/Core>
#include <limits>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "physics/config.hpp"
#include "predictor/dataset.hpp"

namespace dw::physics {
class WrenchModel;
}

namespace dw::predictor {

class ForceModel {
public:
    virtual ~ForceModel() = default;
    virtual const std::string& name() const = 0;
    virtual Wrench6 predict(std::span<const RelState> neighbours) const = 0;
    // A recorded sample of `source`: the physics uses each vehicle's parameters and the sufferer's
    // height, the learnt models each body's mass.
    virtual Wrench6 predict(const Sample& s, const Source& source) const {
        (void)source;
        return predict(s.neighbours());
    }
    // The physics the model is or carries (a physics model, a correction composed with its
    // physics), whose noise model its predictions' intervals take; null for a learnt model alone.
    virtual const physics::PhysicsConfig* physics() const { return nullptr; }
};

// Another model's prediction recorded with the flight (reference.csv, e.g. the vehicle's own
// onboard network), read off each sample; it predicts nothing where a flight has none.
class ReferenceModel final : public ForceModel {
public:
    const std::string& name() const override;
    Wrench6 predict(std::span<const RelState>) const override { return kNoPrediction; }
    Wrench6 predict(const Sample& s, const Source&) const override { return s.recorded_prediction; }
};

// A model plus another's correction (physics-informed: the learnt model trained on what the
// physics leaves, recorded less physics). Named "<base>+<correction>".
class CorrectedModel final : public ForceModel {
public:
    CorrectedModel(const ForceModel& base, const ForceModel& correction)
        : base_(base), correction_(correction), name_(base.name() + "+" + correction.name()) {}
    const std::string& name() const override { return name_; }
    Wrench6 predict(std::span<const RelState> neighbours) const override {
        return sum(base_.predict(neighbours), correction_.predict(neighbours));
    }
    Wrench6 predict(const Sample& s, const Source& source) const override {
        return sum(base_.predict(s, source), correction_.predict(s, source));
    }

private:
    static Wrench6 sum(Wrench6 a, const Wrench6& b) {
        for (std::size_t k = 0; k < a.size(); ++k) a[k] += b[k];
        return a;
    }
    const ForceModel& base_;
    const ForceModel& correction_;
    std::string name_;
};

// A dense layer: out = act(W in + b). Activation "silu" or "linear".
struct Layer {
    Eigen::MatrixXf w;
    Eigen::VectorXf b;
    bool silu = true;
};
struct Mlp {
    std::vector<Layer> layers;
    Eigen::VectorXf forward(const Eigen::VectorXf& in) const;
    int inputs() const { return layers.empty() ? 0 : static_cast<int>(layers.front().w.cols()); }
    int outputs() const { return layers.empty() ? 0 : static_cast<int>(layers.back().w.rows()); }
};

enum class Structure { sum, deep_sets };

inline constexpr int kFeatureSize = 12;
using Features = std::array<double, kFeatureSize>;
inline constexpr std::array<const char*, kFeatureSize> kFeatureNames{"dn",
                                                                     "de",
                                                                     "dd",
                                                                     "dvn",
                                                                     "dve",
                                                                     "dvd",
                                                                     "horizontal_distance",
                                                                     "distance_over_separation",
                                                                     "inverse_separation",
                                                                     "neighbour_mass",
                                                                     "sufferer_mass",
                                                                     "jet_overlap"};
inline constexpr std::size_t kNeighbourMassFeature = 9;
inline constexpr std::size_t kSuffererMassFeature = 10;
inline constexpr std::size_t kOverlapFeature = kFeatureSize - 1;  // not normalised: mean 0, spread 1
// The bodies behind a sample's relative states: their masses [kg], what tells a 32 g neighbour's jet
// from a 67 g one's and a small sufferer from a large one. NaN: not known (a bare set of relative
// states: the contour maps, the online node), served as the training set's mean mass.
inline constexpr double kUnknownMass = std::numeric_limits<double>::quiet_NaN();
struct Bodies {
    double sufferer_kg = kUnknownMass;
    std::array<double, kMaxNeighbours> neighbour_kg{kUnknownMass, kUnknownMass, kUnknownMass};
};
Bodies bodies_of(const Sample& s, const Source& source);  // from the flight's own parameters
// A feature that took one value in training (every vehicle of one mass, as in the simulated lab)
// taught the model nothing: its spread is saved as this, so that served it weighs nothing, whatever
// its value (a simulated lab's model on a flight of other vehicles is not thrown off by their mass).
inline constexpr float kUnvariedStd = 1e20F;
// The vertical separation's offset in the two ratios [m]: about a rotor's size, so a neighbour level
// with the sufferer gives finite features (the jet's virtual origin lies about that far above a rotor).
inline constexpr double kFeatureSeparationOffsetM = 0.1;
// Two jets' overlap at the sufferer: exp(-(q / kJetOverlapRatio)^2), q = the horizontal distance
// between the two neighbours over the sum of their depths above the sufferer (each + the offset).
// A turbulent round jet's half-width grows by about 0.1 of its depth and its edge lies at about
// twice that, so two jets' edges meet near q = 0.2.
inline constexpr double kJetOverlapRatio = 0.2;
double jet_overlap(const RelState& a, const RelState& b);
// One neighbour alone (overlap 0); j in its set (the largest overlap with another).
Features features_of(const RelState& x, double neighbour_kg = kUnknownMass, double sufferer_kg = kUnknownMass);
Features features_of(std::span<const RelState> set, std::size_t j, const Bodies& bodies = {});

inline constexpr const char* kModelFormat = "downwash-model/4";
// The learnt models' kinds, as model files and --kind name them.
inline constexpr std::array<const char*, 3> kModelKinds = {"naive_linear", "learnt_linear", "deep_sets"};

class LearntModel final : public ForceModel {
public:
    std::string kind;  // one of kModelKinds (the model's name)
    Structure structure = Structure::sum;
    std::array<float, kFeatureSize> input_mean{}, input_std{};
    std::array<float, 6> output_scale{};
    Mlp phi;       // per neighbour (psi for the sum structure)
    Mlp rho;       // deep sets: on the pooled sum
    Mlp baseline;  // deep sets: a sum model's psi (trained on with it) added to the output (empty: none)
    std::string metadata_json = "{}";  // what it was trained on, how, and how well

    const std::string& name() const override { return kind; }
    Wrench6 predict(std::span<const RelState> neighbours) const override { return predict(neighbours, Bodies{}); }
    Wrench6 predict(const Sample& s, const Source& source) const override {
        return predict(s.neighbours(), bodies_of(s, source));
    }
    Wrench6 predict(std::span<const RelState> neighbours, const Bodies& bodies) const;
    // Deep Sets on a baseline: its term weighed by the jet overlap, less Phi(0) (above).
    bool residual() const { return structure == Structure::deep_sets && !baseline.layers.empty(); }
    // Deep Sets on a baseline without its set term: Σ psi, the sum model that trained beside it.
    LearntModel sum_part() const;
    // What this model sees of neighbour j (training and serving): a sum model one neighbour alone.
    Features features(std::span<const RelState> set, std::size_t j, const Bodies& bodies) const {
        return structure == Structure::deep_sets ? features_of(set, j, bodies)
                                                 : features_of(set[j], bodies.neighbour_kg[j], bodies.sufferer_kg);
    }
    // Features in the model's normalisation (an unknown mass: the training set's mean).
    float normalised(const Features& f, std::size_t i) const {
        return std::isnan(f[i]) ? 0.0f : (static_cast<float>(f[i]) - input_mean[i]) / input_std[i];
    }

    void save(const std::string& path) const;
    // Throws dw::InputError naming the file and the field for a malformed model.
    static LearntModel load(const std::string& path);
};

class PhysicsModel final : public ForceModel {
public:
    explicit PhysicsModel(const physics::PhysicsConfig& config, std::string name = "physics");
    ~PhysicsModel() override;
    const std::string& name() const override { return name_; }
    Wrench6 predict(std::span<const RelState> neighbours) const override;
    Wrench6 predict(const Sample& s, const Source& source) const override;
    const physics::PhysicsConfig& config() const { return config_; }
    const physics::PhysicsConfig* physics() const override { return &config_; }

private:
    const physics::WrenchModel& model_for(const physics::VehicleParams& sufferer) const;
    std::string name_;
    physics::PhysicsConfig config_;
    std::unique_ptr<physics::WrenchModel> model_;
    double stand_height_ = 1.4;
    mutable std::mutex mutex_;  // guards the per-sufferer models
    mutable std::vector<std::pair<physics::VehicleParams, std::unique_ptr<physics::WrenchModel>>> by_sufferer_;
};

// A learnt correction to a physics (dw-predictor real's models/<kind>_on_physics.json, trained on
// what the physics leaves) carries the physics it corrects (metadata key kCorrectsPhysicsKey: its
// YAML), so that wherever a model file is loaded (compare, map, the online node) it is served
// composed: physics + correction, named "physics+<kind>". A correction alone is no model.
inline constexpr const char* kCorrectsPhysicsKey = "corrects_physics";
inline constexpr const char* kCorrectionFileSuffix = "_on_physics";  // <kind>_on_physics.json
void mark_correction(LearntModel& m, const physics::PhysicsConfig& corrected);

class PhysicsCorrection final : public ForceModel {
public:
    PhysicsCorrection(const physics::PhysicsConfig& physics, LearntModel correction)
        : physics_(physics), correction_(std::move(correction)), composed_(physics_, correction_) {}
    const std::string& name() const override { return composed_.name(); }
    Wrench6 predict(std::span<const RelState> neighbours) const override { return composed_.predict(neighbours); }
    Wrench6 predict(const Sample& s, const Source& source) const override { return composed_.predict(s, source); }
    const physics::PhysicsConfig* physics() const override { return &physics_.config(); }

private:
    PhysicsModel physics_;
    LearntModel correction_;
    CorrectedModel composed_;  // of the two above
};

// The mean of several trainings of one model (an ensemble) as one model of their summed width: each
// network's layers side by side, block-diagonal, so that the last layer averages (psi, rho) or
// concatenates (phi, whose outputs feed rho) the members' outputs. Exactly the mean of the members'
// predictions, served as any model is. Throws dw::InputError for members of different kinds or
// normalisations, or none.
LearntModel average_of(std::span<const LearntModel> members);

// Loads a physics configuration (.yaml), a saved learnt model, or a correction composed with the
// physics it carries (PhysicsCorrection). Throws dw::InputError naming the file: also for a file
// named as a correction (kCorrectionFileSuffix) that carries no physics (saved before 2026-12-06).
std::unique_ptr<ForceModel> load_model(const std::string& path);
// Model files side by side (compare, map): each loaded as above and named distinctly — a name that
// two files share becomes "<name> (<file>)" for each, so that no column of a table is ambiguous.
std::vector<std::unique_ptr<ForceModel>> load_models(const std::vector<std::string>& paths);

}  // namespace dw::predictor
