#include "analysis/resimulation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "physics/effect_types.hpp"
#include "physics/recording_chain.hpp"
#include "physics/samplers.hpp"
#include "physics/wrench_model.hpp"

namespace dw::analysis {

Resimulation::Resimulation(const flight::Flight& f, const physics::PhysicsConfig& physics, double grid_hz)
    : bodies_(flight::body_tracks(f)), dt_(1.0 / grid_hz) {
    sufferer_params_ = physics::vehicle_of(f.meta, f.meta.sufferer, physics.sufferer.vehicle);
    neighbour_params_ = physics::neighbours_of(f.meta, physics);
    for (const auto& v : neighbour_params_) near_radius_.push_back(physics::near_radius(v));
    flying_ = !f.meta.stand_height_m.has_value();
    residual_ = f.meta.wrench_source == flight::WrenchSource::residual;
    if (!f.meta.moments_measured) measured_axes_ = {true, true, true, false, false, false};
    for (const auto& w : f.wrench) {
        stamps_.push_back(w.t);
        measured_.push_back(w.w);
    }
    if (stamps_.empty()) throw InputError("wrench.csv: no samples");
    const auto& st = bodies_.sufferer.t;
    // The grid covers the poses and the wrench stamps, with a margin for time shifts.
    t0_ = std::min(st.front(), stamps_.front()) - 1.0;
    const double t1 = std::max(st.back(), stamps_.back()) + 1.0;
    n_ = static_cast<std::size_t>(std::ceil((t1 - t0_) / dt_)) + 1;
    grid_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
        const double t = t0_ + static_cast<double>(i) * dt_;
        auto& g = grid_[i];
        g.sufferer = sufferer(t);
        g.sufferer_velocity = bodies_.sufferer.velocity_at(t);
        for (std::size_t j = 0; j < bodies_.neighbours.size(); ++j) {
            const auto p = position(static_cast<int>(j), t);
            const auto v = velocity(static_cast<int>(j), t);
            const auto& tr = bodies_.neighbours[j];
            auto it = std::lower_bound(tr.t.begin(), tr.t.end(), t);
            const auto k = static_cast<std::size_t>(
                std::min<std::ptrdiff_t>(it - tr.t.begin(), static_cast<std::ptrdiff_t>(tr.t.size()) - 1));
            const auto& q = tr.q[k];
            const physics::Vec3 axis = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized() * physics::Vec3::UnitZ();
            g.neighbours.push_back({p[0], p[1], p[2], v[0], v[1], v[2], axis.x(), axis.y(), axis.z()});
        }
    }
}

std::array<double, 3> Resimulation::position(int j, double t) const {
    return bodies_.neighbours[static_cast<std::size_t>(j)].position_at(t);
}

std::array<double, 3> Resimulation::velocity(int j, double t) const {
    return bodies_.neighbours[static_cast<std::size_t>(j)].velocity_at(t);
}

std::array<double, 3> Resimulation::sufferer(double t) const { return bodies_.sufferer.position_at(t); }

std::array<double, 3> Resimulation::sufferer_velocity(double t) const { return bodies_.sufferer.velocity_at(t); }

namespace {

// The part of a configuration that changes the air's wrench (not the recording's view of it).
physics::PhysicsConfig flow_part(const physics::PhysicsConfig& c) {
    physics::PhysicsConfig f = c;
    for (const auto* t : physics::effect_types())  // the recording's view and the sufferer's own forces
        if (!t->changes_flow()) t->clear(f.effects);
    f.turbulence.enabled = false;  // the mean flow
    f.discrepancy.clear();         // a correction to the recording, not the air
    return f;
}

}  // namespace

physics::PhysicsConfig Resimulation::flow_of(const physics::PhysicsConfig& c) const {
    physics::PhysicsConfig flow = flow_part(c);
    flow.sufferer.vehicle = sufferer_params_;
    return flow;
}

std::vector<physics::Jet> Resimulation::jets_of(const physics::PhysicsConfig& flow) const {
    std::vector<physics::Jet> jets;
    for (const auto& v : neighbour_params_) jets.push_back(physics::Jet::make(v, flow));
    return jets;
}

const std::vector<Wrench6>& Resimulation::air(const physics::PhysicsConfig& c) const {
    physics::PhysicsConfig flow = flow_of(c);
    const KeyValues key = physics::key_values(flow);  // only read
    if (auto it = cache_.find(key); it != cache_.end()) return it->second;
    const physics::WrenchModel model(flow);
    const std::vector<physics::Jet> jets = jets_of(flow);
    const auto& fx = flow.effects;
    const physics::Vec3 offset =
        physics::RecordingChain(fx).position_error_m();  // the motion capture's, on the neighbours
    const auto& types = physics::effect_types();
    const bool far_is_zero = std::none_of(types.begin(), types.end(),
                                          [&](const auto* t) { return t->acts_far_from_jets() && t->enabled(fx); });
    std::vector<Wrench6> out(n_, Wrench6{});
    std::vector<physics::Producer> ps(bodies_.neighbours.size());
    for (std::size_t i = 0; i < n_; ++i) {
        const physics::Vec3 suf = producers_at(i, model, jets, offset, ps);
        if (far_is_zero && !near(suf, ps)) continue;
        const physics::Wrench w = model.evaluate(suf, ps);
        if (!w.allFinite())
            throw InputError(
                log::cat("the physics gave a non-finite wrench at t = ", t0_ + static_cast<double>(i) * dt_,
                         " s of the recorded flight: check meta.json's vehicles and the physics configuration"));
        out[i] = physics::to_wrench6(w);
    }
    if (cache_order_.size() >= 12) {  // a few flows: the fits revisit the last ones
        cache_.erase(cache_order_.front());
        cache_order_.erase(cache_order_.begin());
    }
    cache_order_.push_back(key);
    return cache_.emplace(key, std::move(out)).first->second;
}

physics::Vec3 Resimulation::producers_at(std::size_t i, const physics::WrenchModel& model,
                                         const std::vector<physics::Jet>& jets, const physics::Vec3& offset,
                                         std::vector<physics::Producer>& ps) const {
    const auto& g = grid_[i];
    for (std::size_t j = 0; j < bodies_.neighbours.size(); ++j) {
        const auto& x = g.neighbours[j];
        const physics::Vec3 pos = physics::Vec3(x[0], x[1], x[2]) - offset;  // recorded = true + offset
        ps[j] = model.producer(pos, physics::Vec3(x[3], x[4], x[5]));
        ps[j].axis = physics::Vec3(x[6], x[7], x[8]);
        ps[j].jet = jets[j];
    }
    return physics::Vec3(g.sufferer[0], g.sufferer[1], g.sufferer[2]);
}

bool Resimulation::near(const physics::Vec3& suf, const std::vector<physics::Producer>& ps) const {
    for (std::size_t j = 0; j < ps.size(); ++j)
        if (std::hypot(ps[j].position.x() - suf.x(), ps[j].position.y() - suf.y()) < near_radius_[j]) return true;
    return false;
}

void Resimulation::at_stamps(const physics::PhysicsConfig& c, const AtStamp& f) const {
    if (n_ == 0) return;
    const physics::PhysicsConfig flow = flow_of(c);
    const physics::WrenchModel model(flow);
    const std::vector<physics::Jet> jets = jets_of(flow);
    std::vector<physics::Producer> ps(bodies_.neighbours.size());
    for (std::size_t k = 0; k < stamps_.size(); ++k) {
        const double x = std::round((stamps_[k] - t0_) / dt_);
        const auto i = static_cast<std::size_t>(std::clamp(x, 0.0, static_cast<double>(n_ - 1)));
        const physics::Vec3 suf = producers_at(i, model, jets, physics::Vec3::Zero(), ps);
        f(k, suf, model, ps);
    }
}

std::vector<Wrench6> Resimulation::buffeting_sigma(const physics::PhysicsConfig& c) const {
    std::vector<Wrench6> out(stamps_.size(), Wrench6{});
    if (!c.turbulence.enabled || c.turbulence.lateral_intensity <= 0) return out;
    at_stamps(c, [&](std::size_t k, const physics::Vec3& suf, const physics::WrenchModel& model,
                     const std::vector<physics::Producer>& ps) {
        out[k] = physics::to_wrench6(model.buffeting_sigma(suf, ps, c.turbulence.lateral_intensity));
    });
    return out;
}

std::vector<double> Resimulation::shared_push(const physics::PhysicsConfig& c) const {
    std::vector<double> out(stamps_.size(), 0.0);
    if (bodies_.neighbours.size() < 2) return out;
    at_stamps(c, [&](std::size_t k, const physics::Vec3& suf, const physics::WrenchModel& model,
                     const std::vector<physics::Producer>& ps) {
        if (!near(suf, ps)) return;
        double sum = 0, strongest = 0;
        for (const auto& p : ps) {
            const double push = model.evaluate(suf, std::span<const physics::Producer>(&p, 1)).head<3>().norm();
            sum += push, strongest = std::max(strongest, push);
        }
        if (sum > 0 && std::isfinite(sum)) out[k] = 1.0 - strongest / sum;
    });
    return out;
}

std::vector<Wrench6> Resimulation::recorded(const physics::PhysicsConfig& c) const {
    physics::ChainInput in;
    in.t.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) in.t[i] = t0_ + static_cast<double>(i) * dt_;
    in.force = air(c);
    in.sufferer = [this, &c](std::size_t i) {
        const auto& g = grid_[i];
        return physics::sufferer_state(
            c, sufferer_params_, physics::Vec3(g.sufferer[0], g.sufferer[1], g.sufferer[2]),
            physics::Vec3(g.sufferer_velocity[0], g.sufferer_velocity[1], g.sufferer_velocity[2]));
    };
    // A stand's recording is zeroed over its first tare_s; a residual source is tared by its
    // importer where no neighbour is near, where the physics gives no force either.
    in.tare_s = tare_s(c);
    in.recorded = &measured_;
    physics::StampSampler at_stamps(stamps_, residual_ ? nullptr : &c.stand);
    return physics::RecordingChain(c.effects).record(std::move(in), at_stamps).w;
}

double Resimulation::tare_s(const physics::PhysicsConfig& c) const { return residual_ ? 0.0 : c.stand.tare_s; }

std::size_t Resimulation::tare_samples(const physics::PhysicsConfig& c) const {
    return physics::tare_count(stamps_, tare_s(c));
}

std::vector<SampleInfo> describe(const Resimulation& r, const flight::Blocks& blocks, const physics::PhysicsConfig& c) {
    auto info = describe(r, blocks);
    const auto shared = r.shared_push(c);
    for (std::size_t i = 0; i < info.size(); ++i) info[i].shared = shared[i];
    return info;
}

std::vector<SampleInfo> describe(const Resimulation& r, const flight::Blocks& blocks) {
    std::vector<SampleInfo> out(r.stamps().size());
    flight::BlockCursor block(blocks.blocks);
    for (std::size_t i = 0; i < out.size(); ++i) {
        const double t = r.stamps()[i];
        auto& s = out[i];
        const auto suf = r.sufferer(t);
        double vn = 0, ve = 0, low = -1e9;
        s.offset = INFINITY;
        for (int j = 0; j < r.neighbours(); ++j) {
            const auto p = r.position(j, t);
            const auto v = r.velocity(j, t);
            s.n += (p[0] - suf[0]) / r.neighbours();
            s.e += (p[1] - suf[1]) / r.neighbours();
            low = std::max(low, p[2] - suf[2]);
            vn += v[0] / r.neighbours();
            ve += v[1] / r.neighbours();
            const double horizontal = std::hypot(p[0] - suf[0], p[1] - suf[1]);
            s.near = s.near || horizontal < r.near_radius(j);
            if (horizontal < s.offset) s.offset = horizontal, s.above = suf[2] - p[2];
        }
        s.h = -low;
        s.speed = std::hypot(vn, ve);
        if (blocks.kind == flight::BlockKind::legs) s.direction = ve > 0.1 ? 1 : (ve < -0.1 ? -1 : 0);
        if (const auto* leg = block.at(t)) {
            s.leg = leg->leg;
            s.leg_fraction = (t - leg->t_start) / std::max(1e-9, leg->t_end - leg->t_start);
        }
    }
    return out;
}

}  // namespace dw::analysis
