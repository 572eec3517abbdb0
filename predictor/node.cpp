#include "predictor/node.hpp"

#include "predictor/intervals.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/time.hpp"
#include "physics/bodies.hpp"
#include "physics/plausible.hpp"

namespace dw::predictor {

std::array<double, 3> FrameFeatures::velocity(History& h, double t, const std::array<double, 3>& p) {
    while (!h.p.empty() && (h.p.back().first >= t || t - h.p.back().first > 0.1))
        h.p.clear();  // gap or reorder: restart
    h.p.emplace_back(t, p);
    while (h.p.size() > 2 && t - h.p[1].first >= 0.02) h.p.pop_front();  // keep ~20 ms of history
    if (h.p.size() < 2) return {0, 0, 0};
    const auto& [t0, p0] = h.p.front();
    const double dt = t - t0;
    return {(p[0] - p0[0]) / dt, (p[1] - p0[1]) / dt, (p[2] - p0[2]) / dt};
}

std::optional<FrameNeighbours> FrameFeatures::update(const msg::MocapFrame& frame) {
    const double t = to_seconds(dds::from_msg(frame.header().stamp()));
    std::array<double, 3> ps{}, vs{};
    bool have_sufferer = false;
    struct Other {
        const std::string* name;
        std::array<double, 3> p, v;
    };
    std::vector<Other> others;
    for (const auto& b : frame.bodies()) {
        // A body that is no measurement (issue 70: NaN or 1e300 from a wire) is not there.
        if (!b.tracking_valid() ||
            !physics::plausible_position(Eigen::Vector3d(b.position_m().x(), b.position_m().y(), b.position_m().z())))
            continue;
        const std::array<double, 3> p{b.position_m().x(), b.position_m().y(), b.position_m().z()};
        const auto v = velocity(history_[b.name()], t, p);
        if (b.name() == sufferer_) {
            ps = p;
            vs = v;
            have_sufferer = true;
        } else if (is_neighbour(b.name())) {
            others.push_back({&b.name(), p, v});
        }
    }
    if (!have_sufferer) return std::nullopt;
    FrameNeighbours out;
    out.t = t;
    out.sufferer_height_m = -ps[2];  // NED: d is minus the height above the floor
    for (const auto& [name, p, v] : others) {
        const RelState r{p[0] - ps[0], p[1] - ps[1], p[2] - ps[2], v[0] - vs[0], v[1] - vs[1], v[2] - vs[2]};
        if (std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) > max_distance_m_) continue;
        out.x.push_back(r);
        out.names.push_back(*name);
        if (out.x.size() == static_cast<std::size_t>(kMaxNeighbours)) break;
    }
    return out;
}

bool FrameFeatures::is_neighbour(const std::string& name) const {
    return neighbours_.empty() || std::find(neighbours_.begin(), neighbours_.end(), name) != neighbours_.end();
}

OnlineBodies::OnlineBodies(const flight::Meta& meta, const std::string& path)
    : sufferer_(meta.sufferer), neighbours_(meta.neighbours) {
    if (neighbours_.size() > static_cast<std::size_t>(kMaxNeighbours))
        throw InputError(
            log::cat(path, ": neighbours: ", neighbours_.size(), " (the models take at most ", kMaxNeighbours, ")"));
    std::vector<std::string> bodies = neighbours_;
    bodies.push_back(sufferer_);
    for (const auto& b : bodies)
        if (!meta.vehicles.contains(b))
            throw InputError(log::cat(path, ": vehicles: '", b, "' has no parameters (each body's are needed online)"));
    source_.name = "online";
    source_.sufferer = physics::vehicle_of(meta, sufferer_, {});
    source_.neighbours = physics::neighbours_of(meta, {});
    source_.flying = !meta.stand_height_m.has_value();
    for (std::size_t j = 0; j < neighbours_.size(); ++j) index_[neighbours_[j]] = static_cast<std::uint8_t>(j);
}

Sample OnlineBodies::sample(const FrameNeighbours& f) const {
    Sample s;
    s.t = f.t;
    s.k = static_cast<int>(f.x.size());
    s.height = f.sufferer_height_m;
    for (std::size_t j = 0; j < f.x.size(); ++j) {
        s.x[j] = f.x[j];
        s.who[j] = index_.at(f.names[j]);  // FrameFeatures keeps meta.json's neighbours only
    }
    return s;
}

namespace {

std::optional<OnlineBodies> bodies_from(const NodeOptions& o) {
    if (o.vehicles_path.empty()) return std::nullopt;
    return OnlineBodies(flight::read_meta(o.vehicles_path), o.vehicles_path);
}

}  // namespace

PredictorNode::PredictorNode(dds::Participant& p, const NodeOptions& o, const Clock& clock)
    : options_(o),
      clock_(clock),
      model_(load_model(o.model_path)),
      bodies_(bodies_from(o)),
      noise_(o.noise_path.empty() ? std::nullopt : std::optional(physics::load_physics(o.noise_path))),
      features_(bodies_ ? bodies_->sufferer() : o.sufferer,
                bodies_ ? bodies_->neighbours() : std::vector<std::string>{}),
      writer_(p, dds::topics::wrench_prediction) {
    // Predictions are written from the reader's callback: wait for the required readers first.
    writer_.await_readers();
    reader_.emplace(p, dds::topics::mocap_frame,
                    [this](const msg::MocapFrame& f, const dds::SampleMeta&) { on_frame(f); });
    log::info("predicting with ", model_->name(), " (", o.model_path, ") for '",
              bodies_ ? bodies_->sufferer() : o.sufferer, "'",
              bodies_ ? log::cat(", each body as ", o.vehicles_path, " describes it") : std::string());
    watcher_ = std::thread([this] { watch(); });
}

PredictorNode::~PredictorNode() {
    stop_ = true;
    if (watcher_.joinable()) watcher_.join();
}

std::string PredictorNode::model_name() const {
    std::lock_guard lock(mutex_);
    return model_->name();
}

void PredictorNode::on_frame(const msg::MocapFrame& frame) {
    // A stamp off the stream's time (issue 70) would be published as a prediction's time: refused.
    if (!stamps_.accept(dds::from_msg(frame.header().stamp()))) {
        if (stray_stamps_.fetch_add(1) == 0)
            log::warn("a mocap frame refused (the first; counted): its stamp is more than ", kMaxStampStepS,
                      " s off the frames' own time (garbled or forged)");
        return;
    }
    const auto x = features_.update(frame);
    if (!x) return;
    std::shared_ptr<const ForceModel> model;
    {
        std::lock_guard lock(mutex_);
        model = model_;
    }
    Wrench6 w{};
    try {
        w = predict(*model, *x);
    } catch (const InputError& e) {  // a geometry the physics cannot take: that frame unpredicted, counted
        if (unpredicted_.fetch_add(1) == 0) log::warn("a frame left unpredicted (the first; counted): ", e.what());
        return;
    }
    // Never a prediction on the wire that a stand could not measure (issue 70): a NaN body, or a
    // model whose weights overflow, leaves that frame unpredicted.
    if (!physics::plausible_wrench(w)) {
        if (unpredicted_.fetch_add(1) == 0)
            log::warn("a frame left unpredicted (the first; counted): ", model->name(),
                      " gave a wrench for it that is not finite or beyond ", physics::kMaxPlausibleForceN, " N or ",
                      physics::kMaxPlausibleTorqueNm, " N·m (a body's position, or the model's weights)");
        return;
    }
    msg::WrenchPrediction out;
    out.header().stamp(frame.header().stamp());
    out.header().run_id(frame.header().run_id());
    out.model_name(model->name());
    out.force_n().x(w[0]);
    out.force_n().y(w[1]);
    out.force_n().z(w[2]);
    out.torque_nm().x(w[3]);
    out.torque_nm().y(w[4]);
    out.torque_nm().z(w[5]);
    out.input_age_s(static_cast<double>(clock_.now_ns() - dds::from_msg(frame.header().stamp())) * 1e-9);
    out.f_d_interval_n(f_d_interval(*model, to_seconds(dds::from_msg(frame.header().stamp())), w[kFdAxis]));
    if (writer_.write(out)) ++published_;
}

double PredictorNode::f_d_interval(const ForceModel& model, double t, double f_d) {
    const physics::PhysicsConfig* noise = model.physics() ? model.physics() : (noise_ ? &*noise_ : nullptr);
    if (!noise) return 0;
    if (model.name() != push_rate_model_) push_rate_ = {}, push_rate_model_ = model.name();  // a new model's own rate
    const double rate = push_rate_.update(t, f_d);
    return f_d_half_width(*noise, bodies_ ? bodies_->source().sufferer : noise->sufferer.vehicle, f_d, rate);
}

Wrench6 PredictorNode::predict(const ForceModel& model, const FrameNeighbours& f) const {
    if (!bodies_) return model.predict(f.x);
    return model.predict(bodies_->sample(f), bodies_->source());
}

void PredictorNode::watch() {
    namespace fs = std::filesystem;
    std::error_code ec;
    auto last = fs::last_write_time(options_.model_path, ec);
    while (!stop_) {
        std::this_thread::sleep_for(std::chrono::duration<double>(options_.reload_check_s));
        const auto now = fs::last_write_time(options_.model_path, ec);
        if (ec || now == last) continue;
        last = now;
        try {
            std::shared_ptr<const ForceModel> m = load_model(options_.model_path);
            {
                std::lock_guard lock(mutex_);
                model_ = m;
            }
            ++reloads_;
            log::info("model swapped: now ", m->name(), " (", options_.model_path, ")");
        } catch (const std::exception& e) {
            log::error("model not swapped, keeping the old one: ", e.what());
        }
    }
}

}  // namespace dw::predictor
