#include "predictor/model.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/names.hpp"
#include "core/errors.hpp"
#include "core/config.hpp"
#include "core/files.hpp"
#include "core/keys.hpp"
#include "core/log.hpp"
#include "flight/flight.hpp"
#include "physics/wrench_model.hpp"

namespace dw::predictor {

Eigen::VectorXf Mlp::forward(const Eigen::VectorXf& in) const {
    Eigen::VectorXf x = in;
    for (const auto& l : layers) {
        Eigen::VectorXf y = l.w * x + l.b;
        if (l.silu) y = y.array() / (1.0f + (-y.array()).exp());
        x = std::move(y);
    }
    return x;
}

Features features_of(const RelState& x, double neighbour_kg, double sufferer_kg) {
    const double horizontal = std::hypot(x[0], x[1]);
    const double separation = std::abs(x[2]) + kFeatureSeparationOffsetM;
    return {x[0],         x[1],        x[2], x[3], x[4], x[5], horizontal, horizontal / separation, 1.0 / separation,
            neighbour_kg, sufferer_kg, 0.0};
}

Bodies bodies_of(const Sample& s, const Source& source) {
    Bodies b;
    b.sufferer_kg = source.sufferer.mass_kg;
    for (int j = 0; j < s.k; ++j) {
        const std::size_t who = s.who[static_cast<std::size_t>(j)];
        if (who < source.neighbours.size())
            b.neighbour_kg[static_cast<std::size_t>(j)] = source.neighbours[who].mass_kg;
    }
    return b;
}

double jet_overlap(const RelState& a, const RelState& b) {
    const double q = std::hypot(a[0] - b[0], a[1] - b[1]) /
                     (std::abs(a[2]) + std::abs(b[2]) + 2 * kFeatureSeparationOffsetM) / kJetOverlapRatio;
    return std::exp(-q * q);
}

Features features_of(std::span<const RelState> set, std::size_t j, const Bodies& bodies) {
    Features f = features_of(set[j], bodies.neighbour_kg[j], bodies.sufferer_kg);
    for (std::size_t k = 0; k < set.size(); ++k)
        if (k != j) f[kOverlapFeature] = std::max(f[kOverlapFeature], jet_overlap(set[j], set[k]));
    return f;
}

Wrench6 LearntModel::predict(std::span<const RelState> neighbours, const Bodies& bodies) const {
    Eigen::VectorXf pooled = Eigen::VectorXf::Zero(phi.outputs());
    Eigen::VectorXf base = Eigen::VectorXf::Zero(6);
    Eigen::VectorXf in(kFeatureSize);
    const bool deep = structure == Structure::deep_sets, residual = this->residual();
    for (std::size_t j = 0; j < neighbours.size(); ++j) {
        const Features f = features(neighbours, j, bodies);
        for (std::size_t i = 0; i < f.size(); ++i) in[static_cast<Eigen::Index>(i)] = normalised(f, i);
        pooled += static_cast<float>(residual ? f[kOverlapFeature] : 1.0) * phi.forward(in);
        in[kOverlapFeature] = 0;  // the baseline is a sum model: one neighbour at a time
        if (residual) base += baseline.forward(in);
    }
    if (residual) pooled = rho.forward(pooled) - rho.forward(Eigen::VectorXf::Zero(pooled.size()));
    else if (deep) pooled = rho.forward(pooled);
    const Eigen::VectorXf out = pooled + base;
    Wrench6 w{};
    for (std::size_t a = 0; a < 6; ++a) w[a] = static_cast<double>(out[static_cast<Eigen::Index>(a)] * output_scale[a]);
    return w;
}

LearntModel LearntModel::sum_part() const {
    LearntModel s = *this;
    s.kind = kind + "_sum_part";
    s.structure = Structure::sum;
    s.phi = baseline;
    s.rho = {};
    s.baseline = {};
    return s;
}

namespace {

// How one network of the members sits in the combined one: whether its input is the shared features
// (else each member's own slice of the previous network's output) and whether its output is averaged
// (else each member's own slice).
struct Combine {
    bool shared_input;
    bool averaged_output;
};

Mlp side_by_side(std::span<const LearntModel> members, const Mlp LearntModel::*net, Combine how) {
    const auto n = static_cast<Eigen::Index>(members.size());
    const Mlp& first = members.front().*net;
    Mlp out;
    for (std::size_t l = 0; l < first.layers.size(); ++l) {
        const bool shared = how.shared_input && l == 0, averaged = how.averaged_output && l + 1 == first.layers.size();
        const auto rows = first.layers[l].w.rows(), cols = first.layers[l].w.cols();
        Layer c{Eigen::MatrixXf::Zero(averaged ? rows : rows * n, shared ? cols : cols * n),
                Eigen::VectorXf::Zero(averaged ? rows : rows * n), first.layers[l].silu};
        for (Eigen::Index m = 0; m < n; ++m) {
            const Layer& from = (members[static_cast<std::size_t>(m)].*net).layers.at(l);
            if (from.w.rows() != rows || from.w.cols() != cols)
                throw InputError(log::cat("averaging models: member ", m + 1, "'s layer ", l + 1, " is ", from.w.rows(),
                                          " x ", from.w.cols(), ", the first's ", rows, " x ", cols));
            const float scale = averaged ? 1.0f / static_cast<float>(n) : 1.0f;
            c.w.block(averaged ? 0 : m * rows, shared ? 0 : m * cols, rows, cols) += scale * from.w;
            c.b.segment(averaged ? 0 : m * rows, rows) += scale * from.b;
        }
        out.layers.push_back(std::move(c));
    }
    return out;
}

}  // namespace

LearntModel average_of(std::span<const LearntModel> members) {
    if (members.empty()) throw InputError("averaging models: no members");
    const LearntModel& first = members.front();
    for (const auto& m : members)
        if (m.kind != first.kind || m.structure != first.structure || m.input_mean != first.input_mean ||
            m.input_std != first.input_std || m.output_scale != first.output_scale ||
            m.baseline.layers.size() != first.baseline.layers.size() ||
            m.phi.layers.size() != first.phi.layers.size() || m.rho.layers.size() != first.rho.layers.size())
            throw InputError("averaging models: the members differ in kind, normalisation or depth");
    LearntModel a = first;
    const bool deep = first.structure == Structure::deep_sets;
    a.phi = side_by_side(members, &LearntModel::phi, {.shared_input = true, .averaged_output = !deep});
    a.rho = side_by_side(members, &LearntModel::rho, {.shared_input = false, .averaged_output = true});
    a.baseline = side_by_side(members, &LearntModel::baseline, {.shared_input = true, .averaged_output = true});
    return a;
}

namespace {

// The model file (kModelFormat), declared once for reading and writing (core/keys.hpp, as JSON).
constexpr Range kFinite{-1e30, 1e30};
constexpr std::array<const char*, 2> kStructureNames{"sum", "deep_sets"};
constexpr std::array<const char*, 2> kActivationNames{"linear", "silu"};

// A key the file must have.
void required(KeyVisitor& k, const std::string& key) { k.require(k.has(key), key, "missing"); }

template <std::size_t N>
void floats(KeyVisitor& k, const std::string& key, std::array<float, N>& a) {
    required(k, key);
    std::array<double, N> d{};
    std::copy(a.begin(), a.end(), d.begin());
    k.numbers(key, d, kFinite, log::cat("expected ", N, " numbers"));
    std::copy(d.begin(), d.end(), a.begin());
}

// One list of words the model was made with (feature or axis names), checked when read.
template <std::size_t N>
void names(KeyVisitor& k, const std::string& key, const std::array<const char*, N>& expected) {
    std::vector<std::string> v(expected.begin(), expected.end());
    const auto want = v;
    k.texts(key, v);
    k.require(v == want, key, "expected " + log::join(want));
}

void layer_keys(KeyVisitor& k, Layer& l) {
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;  // the file's order
    for (const char* key : {"activation", "weight", "bias"}) required(k, key);
    k.enumeration("activation", l.silu, kActivationNames, "activation");
    std::size_t rows = static_cast<std::size_t>(l.w.rows()), cols = static_cast<std::size_t>(l.w.cols());
    std::vector<double> w(rows * cols);
    Eigen::Map<RowMajor>(w.data(), l.w.rows(), l.w.cols()) = l.w.cast<double>();
    k.matrix("weight", w, rows, cols, kFinite);
    l.w = Eigen::Map<const RowMajor>(w.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols))
              .cast<float>();
    std::vector<double> b(l.b.data(), l.b.data() + l.b.size());
    k.values("bias", b, kFinite);
    k.require(b.size() == rows, "bias", log::cat("expected ", rows, " numbers (the weight's rows)"));
    l.b = Eigen::Map<const Eigen::VectorXd>(b.data(), static_cast<Eigen::Index>(b.size())).cast<float>();
}

// An MLP: its layers in order, each taking what the one before gives (`may_be_empty`: none at all).
void mlp_keys(KeyVisitor& k, const std::string& key, Mlp& m, bool may_be_empty = false) {
    std::size_t count = m.layers.size();
    k.list(key, count, [&](KeyVisitor& item, std::size_t i) {
        if (m.layers.size() <= i) m.layers.resize(i + 1);
        layer_keys(item, m.layers[i]);
    });
    m.layers.resize(count);
    k.require(may_be_empty || !m.layers.empty(), key, "expected a non-empty list of layers");
    for (std::size_t i = 1; i < m.layers.size(); ++i)
        k.require(
            m.layers[i].w.cols() == m.layers[i - 1].w.rows(), log::cat(key, "[", i, "].weight"),
            log::cat("takes ", m.layers[i].w.cols(), " inputs but the layer before gives ", m.layers[i - 1].w.rows()));
}

// What the layers must take and give, for each structure.
void shape_rules(KeyVisitor& k, const LearntModel& m) {
    k.require(m.phi.inputs() == kFeatureSize, "phi[0].weight",
              log::cat("takes ", m.phi.inputs(), " inputs, expected ", kFeatureSize));
    if (m.structure == Structure::deep_sets) {
        k.require(m.rho.inputs() == m.phi.outputs(), "rho[0].weight", "does not take phi's output");
        k.require(m.rho.outputs() == 6, "rho", "must give 6 outputs");
    } else {
        k.require(m.phi.outputs() == 6, "phi", "must give 6 outputs");
    }
    if (m.baseline.layers.empty()) return;
    k.require(m.structure == Structure::deep_sets, "baseline", "only a deep_sets model carries a baseline");
    k.require(m.baseline.inputs() == kFeatureSize && m.baseline.outputs() == 6, "baseline",
              log::cat("must take ", kFeatureSize, " inputs and give 6 outputs"));
}

// The file's format tag, checked before its keys (LearntModel::load): another format's keys are
// not this one's, and the tag says why.
void check_format(const YAML::Node& root, const std::string& path) {
    const YAML::Node& doc = root;  // a const lookup never inserts the key
    const YAML::Node format = doc.IsMap() ? doc["format"] : YAML::Node();
    if (format && (!format.IsScalar() || format.Scalar() != kModelFormat))
        fail_at_node(
            path, format, "format",
            log::cat("expected ", kModelFormat,
                     " (models saved before the bodies' masses, downwash-model/1 to /3, must be trained again)"));
}

void model_keys(KeyVisitor& k, LearntModel& m) {
    for (const char* key : {"format", "kind", "structure", "input", "output", "phi"}) required(k, key);
    k.constant("format", kModelFormat);
    k.text("kind", m.kind);
    k.require(find_name(kModelKinds, m.kind).has_value(), "kind",
              unknown_name_problem("model kind", m.kind, kModelKinds));
    k.enumeration("structure", m.structure, kStructureNames, "structure");
    k.section("input", [&](KeyVisitor& in) {
        names(in, "features", kFeatureNames);
        floats(in, "mean", m.input_mean);
        floats(in, "std", m.input_std);
        for (std::size_t i = 0; i < m.input_std.size(); ++i)
            in.require(m.input_std[i] > 0, log::cat("std[", i, "]"), "must be > 0");
        in.require(m.input_mean[kOverlapFeature] == 0 && m.input_std[kOverlapFeature] == 1,
                   log::cat("mean[", kOverlapFeature, "]"), "jet_overlap is not normalised: mean 0 and std 1");
    });
    k.section("output", [&](KeyVisitor& out) {
        names(out, "axes", flight::kAxes);
        floats(out, "scale", m.output_scale);
    });
    mlp_keys(k, "phi", m.phi);
    if (m.structure == Structure::deep_sets) {
        required(k, "rho");
        mlp_keys(k, "rho", m.rho);
    }
    mlp_keys(k, "baseline", m.baseline, true);  // [] (or absent): none
    shape_rules(k, m);
    k.verbatim("metadata", m.metadata_json);
}

}  // namespace

void LearntModel::save(const std::string& path) const {
    LearntModel m = *this;  // the declaration visits what it writes by reference
    write_file(path, write_json_keys([&](KeyVisitor& k) { model_keys(k, m); }));
}

LearntModel LearntModel::load(const std::string& path) {
    const YAML::Node root = load_yaml(read_file(path, "model file"), path, "JSON");  // JSON: YAML's flow style
    check_format(root, path);
    LearntModel m;
    read_keys(root, path, [&](KeyVisitor& k) { model_keys(k, m); });
    return m;
}

PhysicsModel::PhysicsModel(const physics::PhysicsConfig& config, std::string name)
    : name_(std::move(name)),
      config_(config),
      model_(std::make_unique<physics::WrenchModel>(config)),
      stand_height_(config.stand.height_m) {}
PhysicsModel::~PhysicsModel() = default;

Wrench6 PhysicsModel::predict(std::span<const RelState> neighbours) const {
    const physics::Vec3 sufferer(0, 0, -stand_height_);
    std::vector<physics::Producer> ps;
    ps.reserve(neighbours.size());
    for (const auto& x : neighbours)
        ps.push_back(model_->producer(sufferer + physics::Vec3(x[0], x[1], x[2]), physics::Vec3(x[3], x[4], x[5])));
    const physics::Wrench w = model_->evaluate(sufferer, ps);
    return {w[0], w[1], w[2], w[3], w[4], w[5]};
}

const physics::WrenchModel& PhysicsModel::model_for(const physics::VehicleParams& v) const {
    const std::lock_guard lock(mutex_);
    auto same = [&](const physics::VehicleParams& a) {
        return a.mass_kg == v.mass_kg && a.rotors == v.rotors && a.prop_radius_m == v.prop_radius_m &&
               a.motor_distance_m == v.motor_distance_m;
    };
    for (const auto& [params, model] : by_sufferer_)
        if (same(params)) return *model;
    physics::PhysicsConfig c = config_;
    c.sufferer.vehicle = v;
    by_sufferer_.emplace_back(v, std::make_unique<physics::WrenchModel>(c));
    return *by_sufferer_.back().second;
}

Wrench6 PhysicsModel::predict(const Sample& s, const Source& source) const {
    const physics::WrenchModel& model = model_for(source.sufferer);
    const physics::Vec3 sufferer(0, 0, -(source.flying ? s.height : stand_height_));
    std::vector<physics::Producer> ps;
    for (std::size_t j = 0; j < static_cast<std::size_t>(s.k); ++j) {
        const auto& x = s.x[j];
        ps.push_back(model.producer(sufferer + physics::Vec3(x[0], x[1], x[2]), physics::Vec3(x[3], x[4], x[5])));
        if (s.who[j] < source.neighbours.size())
            ps.back().jet = physics::Jet::make(source.neighbours[s.who[j]], config_);
    }
    const physics::Wrench w = model.evaluate(sufferer, ps);
    if (!w.allFinite())
        throw InputError(log::cat(source.name, ": the physics gave a non-finite wrench at t = ", s.t, " s"));
    return {w[0], w[1], w[2], w[3], w[4], w[5]};
}

void mark_correction(LearntModel& m, const physics::PhysicsConfig& corrected) {
    nlohmann::json j = nlohmann::json::parse(m.metadata_json, nullptr, false);
    if (!j.is_object()) j = nlohmann::json::object();
    j[kCorrectsPhysicsKey] = physics::to_yaml(corrected);
    m.metadata_json = j.dump();
}

namespace {
// The physics a correction carries, if it is one.
std::optional<physics::PhysicsConfig> corrected_physics(const LearntModel& m, const std::string& path) {
    const auto j = nlohmann::json::parse(m.metadata_json, nullptr, false);
    const auto it = j.is_object() ? j.find(kCorrectsPhysicsKey) : j.end();
    if (it != j.end()) {
        if (!it->is_string())
            throw InputError(log::cat(path, ": metadata.", kCorrectsPhysicsKey, ": expected the physics' YAML text"));
        return physics::parse_physics(it->get<std::string>(), log::cat(path, ": metadata.", kCorrectsPhysicsKey));
    }
    if (std::filesystem::path(path).stem().string().ends_with(kCorrectionFileSuffix))
        throw InputError(log::cat(path, ": a correction to a physics (*", kCorrectionFileSuffix,
                                  ".json) that does not carry the physics it corrects (metadata.", kCorrectsPhysicsKey,
                                  "; saved before 2026-12-06): alone it is no model; run dw-predictor real again"));
    return std::nullopt;
}
}  // namespace

std::unique_ptr<ForceModel> load_model(const std::string& path) {
    if (path.ends_with(".yaml") || path.ends_with(".yml"))
        return std::make_unique<PhysicsModel>(physics::load_physics(path));
    LearntModel m = LearntModel::load(path);
    if (auto physics = corrected_physics(m, path)) return std::make_unique<PhysicsCorrection>(*physics, std::move(m));
    return std::make_unique<LearntModel>(std::move(m));
}

const std::string& ReferenceModel::name() const {
    static const std::string kName = "reference";
    return kName;
}

namespace {
class RenamedModel final : public ForceModel {
public:
    RenamedModel(std::unique_ptr<ForceModel> model, std::string name)
        : model_(std::move(model)), name_(std::move(name)) {}
    const std::string& name() const override { return name_; }
    Wrench6 predict(std::span<const RelState> neighbours) const override { return model_->predict(neighbours); }
    Wrench6 predict(const Sample& s, const Source& source) const override { return model_->predict(s, source); }
    const physics::PhysicsConfig* physics() const override { return model_->physics(); }

private:
    std::unique_ptr<ForceModel> model_;
    std::string name_;
};
}  // namespace

std::vector<std::unique_ptr<ForceModel>> load_models(const std::vector<std::string>& paths) {
    std::vector<std::unique_ptr<ForceModel>> out;
    std::map<std::string, int> uses;
    for (const auto& p : paths) {
        out.push_back(load_model(p));
        ++uses[out.back()->name()];
    }
    for (std::size_t i = 0; i < out.size(); ++i) {
        const std::string name = out[i]->name();
        if (uses[name] > 1)
            out[i] = std::make_unique<RenamedModel>(std::move(out[i]), log::cat(name, " (", paths[i], ")"));
    }
    return out;
}

}  // namespace dw::predictor
