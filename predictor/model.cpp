#include "predictor/model.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/errors.hpp"
#include "core/files.hpp"
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

Features features_of(const RelState& x) {
    const double horizontal = std::hypot(x[0], x[1]);
    const double separation = std::abs(x[2]) + kFeatureSeparationOffsetM;
    return {x[0], x[1], x[2], x[3], x[4], x[5], horizontal, horizontal / separation, 1.0 / separation};
}

Wrench6 LearntModel::predict(std::span<const RelState> neighbours) const {
    Eigen::VectorXf pooled = Eigen::VectorXf::Zero(phi.outputs());
    Eigen::VectorXf base = Eigen::VectorXf::Zero(6);
    Eigen::VectorXf in(kFeatureSize);
    for (const auto& x : neighbours) {
        const Features f = features_of(x);
        for (std::size_t i = 0; i < f.size(); ++i)
            in[static_cast<Eigen::Index>(i)] = (static_cast<float>(f[i]) - input_mean[i]) / input_std[i];
        pooled += phi.forward(in);
        if (!baseline.layers.empty()) base += baseline.forward(in);
    }
    const Eigen::VectorXf out = (structure == Structure::deep_sets ? rho.forward(pooled) : pooled) + base;
    Wrench6 w{};
    for (std::size_t a = 0; a < 6; ++a) w[a] = static_cast<double>(out[static_cast<Eigen::Index>(a)] * output_scale[a]);
    return w;
}

namespace {

using nlohmann::json;

json to_json(const Mlp& m) {
    json layers = json::array();
    for (const auto& l : m.layers) {
        json w = json::array();
        for (Eigen::Index r = 0; r < l.w.rows(); ++r) {
            json row = json::array();
            for (Eigen::Index c = 0; c < l.w.cols(); ++c) row.push_back(l.w(r, c));
            w.push_back(row);
        }
        json b = json::array();
        for (Eigen::Index r = 0; r < l.b.size(); ++r) b.push_back(l.b[r]);
        layers.push_back({{"activation", l.silu ? "silu" : "linear"}, {"weight", w}, {"bias", b}});
    }
    return layers;
}

struct Reader {
    std::string file;
    [[noreturn]] void fail(const std::string& field, const std::string& what) const {
        throw InputError(log::cat(file, ": ", field, ": ", what));
    }
    const json& at(const json& j, const std::string& key, const std::string& where) const {
        if (!j.is_object() || !j.contains(key)) fail(where + key, "missing");
        return j.at(key);
    }
    template <std::size_t N>
    std::array<float, N> floats(const json& j, const std::string& field) const {
        if (!j.is_array() || j.size() != N) fail(field, log::cat("expected ", N, " numbers"));
        std::array<float, N> a{};
        for (std::size_t i = 0; i < N; ++i) {
            if (!j[i].is_number()) fail(log::cat(field, "[", i, "]"), "not a number");
            a[i] = j[i].get<float>();
        }
        return a;
    }
    Mlp mlp(const json& j, const std::string& field) const {
        if (!j.is_array() || j.empty()) fail(field, "expected a non-empty list of layers");
        Mlp m;
        for (std::size_t i = 0; i < j.size(); ++i) {
            const std::string f = log::cat(field, "[", i, "].");
            const auto& w = at(j[i], "weight", f);
            const auto& b = at(j[i], "bias", f);
            const auto act = at(j[i], "activation", f);
            if (act != "silu" && act != "linear") fail(f + "activation", "expected silu or linear");
            if (!w.is_array() || w.empty() || !w[0].is_array() || w[0].empty()) fail(f + "weight", "expected a matrix");
            if (!b.is_array() || b.size() != w.size()) fail(f + "bias", log::cat("expected ", w.size(), " numbers"));
            Layer l;
            l.silu = act == "silu";
            l.w.resize(static_cast<Eigen::Index>(w.size()), static_cast<Eigen::Index>(w[0].size()));
            l.b.resize(static_cast<Eigen::Index>(w.size()));
            for (std::size_t r = 0; r < w.size(); ++r) {
                if (!w[r].is_array() || w[r].size() != w[0].size())
                    fail(log::cat(f, "weight[", r, "]"), "rows differ in length");
                for (std::size_t c = 0; c < w[r].size(); ++c) {
                    if (!w[r][c].is_number()) fail(log::cat(f, "weight[", r, "][", c, "]"), "not a number");
                    l.w(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = w[r][c].get<float>();
                }
                if (!b[r].is_number()) fail(log::cat(f, "bias[", r, "]"), "not a number");
                l.b[static_cast<Eigen::Index>(r)] = b[r].get<float>();
            }
            if (!m.layers.empty() && m.layers.back().w.rows() != l.w.cols())
                fail(f + "weight",
                     log::cat("takes ", l.w.cols(), " inputs but the layer before gives ", m.layers.back().w.rows()));
            m.layers.push_back(std::move(l));
        }
        return m;
    }
};

}  // namespace

void LearntModel::save(const std::string& path) const {
    json j;
    j["format"] = kModelFormat;
    j["kind"] = kind;
    j["structure"] = structure == Structure::sum ? "sum" : "deep_sets";
    j["input"] = {{"features", kFeatureNames}, {"mean", input_mean}, {"std", input_std}};
    j["output"] = {{"axes", flight::kAxes}, {"scale", output_scale}};
    j["phi"] = to_json(phi);
    if (structure == Structure::deep_sets) j["rho"] = to_json(rho);
    if (!baseline.layers.empty()) j["baseline"] = to_json(baseline);
    j["metadata"] = json::parse(metadata_json);
    write_file(path, j.dump(1) + "\n");
}

LearntModel LearntModel::load(const std::string& path) {
    const std::string text = read_file(path, "model file");
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InputError(log::cat(path, ": not JSON (byte ", e.byte, ")"));
    }
    Reader r{path};
    if (r.at(j, "format", "") != kModelFormat)
        r.fail("format", log::cat("expected ", kModelFormat,
                                  " (models saved before the jet features, downwash-model/1, must be trained again)"));
    LearntModel m;
    const auto& kind = r.at(j, "kind", "");
    if (!kind.is_string()) r.fail("kind", "not a string");
    m.kind = kind.get<std::string>();
    const auto st = r.at(j, "structure", "");
    if (st == "sum") m.structure = Structure::sum;
    else if (st == "deep_sets") m.structure = Structure::deep_sets;
    else r.fail("structure", "expected sum or deep_sets");
    const auto& input = r.at(j, "input", "");
    m.input_mean = r.floats<kFeatureSize>(r.at(input, "mean", "input."), "input.mean");
    m.input_std = r.floats<kFeatureSize>(r.at(input, "std", "input."), "input.std");
    for (std::size_t i = 0; i < m.input_std.size(); ++i)
        if (!(m.input_std[i] > 0)) r.fail(log::cat("input.std[", i, "]"), "must be > 0");
    m.output_scale = r.floats<6>(r.at(r.at(j, "output", ""), "scale", "output."), "output.scale");
    m.phi = r.mlp(r.at(j, "phi", ""), "phi");
    if (m.phi.inputs() != kFeatureSize)
        r.fail("phi[0].weight", log::cat("takes ", m.phi.inputs(), " inputs, expected ", kFeatureSize));
    if (m.structure == Structure::deep_sets) {
        m.rho = r.mlp(r.at(j, "rho", ""), "rho");
        if (m.rho.inputs() != m.phi.outputs()) r.fail("rho[0].weight", "does not take phi's output");
        if (m.rho.outputs() != 6) r.fail("rho", "must give 6 outputs");
    } else if (m.phi.outputs() != 6) {
        r.fail("phi", "must give 6 outputs");
    }
    if (j.contains("baseline")) {
        if (m.structure != Structure::deep_sets) r.fail("baseline", "only a deep_sets model carries a baseline");
        m.baseline = r.mlp(j["baseline"], "baseline");
        if (m.baseline.inputs() != kFeatureSize || m.baseline.outputs() != 6)
            r.fail("baseline", log::cat("must take ", kFeatureSize, " inputs and give 6 outputs"));
    }
    if (j.contains("metadata")) m.metadata_json = j["metadata"].dump();
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

std::unique_ptr<ForceModel> load_model(const std::string& path) {
    if (path.ends_with(".yaml") || path.ends_with(".yml"))
        return std::make_unique<PhysicsModel>(physics::load_physics(path));
    return std::make_unique<LearntModel>(LearntModel::load(path));
}

}  // namespace dw::predictor
