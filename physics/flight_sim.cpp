#include "physics/flight_sim.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "physics/bodies.hpp"
#include "physics/effect_types.hpp"
#include "physics/recording_chain.hpp"
#include "physics/samplers.hpp"
#include "physics/stand.hpp"
#include "physics/vehicle.hpp"

namespace dw::physics {
namespace {

constexpr std::uint64_t kBuffetSeed = 0x9E3779B97F4A7C15ull;  // golden-ratio stride between vehicles

// One jet's turbulence: a multiplier on its speed, and its lateral buffeting (two horizontal
// fluctuations, made perpendicular to its axis). The buffeting's random stream is seeded apart
// from the simulation's master stream, so the other streams stay as they were before it.
class Turbulence {
public:
    Turbulence(const TurbulenceParams& t, Rng gust_rng, Rng buffet_rng)
        : gust_(t.intensity, t.time_scale_s),
          lateral_{OrnsteinUhlenbeck(t.lateral_intensity, t.lateral_time_scale_s),
                   OrnsteinUhlenbeck(t.lateral_intensity, t.lateral_time_scale_s)},
          gust_rng_(gust_rng),
          buffet_rng_(buffet_rng),
          buffeting_(t.lateral_intensity > 0) {}
    void step(double dt, Producer& p) {
        p.gust = std::max(0.0, 1.0 + gust_.step(dt, gust_rng_));
        if (!buffeting_) return;  // off: the gust stays zero, without drawing numbers every step
        const Vec3 g(lateral_[0].step(dt, buffet_rng_), lateral_[1].step(dt, buffet_rng_), 0.0);
        p.lateral_gust = g - g.dot(p.axis) * p.axis;
    }

private:
    OrnsteinUhlenbeck gust_;
    std::array<OrnsteinUhlenbeck, 2> lateral_;
    Rng gust_rng_, buffet_rng_;
    bool buffeting_;
};

void check_finite(double t, const Wrench6& w) {
    if (!std::all_of(w.begin(), w.end(), [](double x) { return std::isfinite(x); })) {
        throw InputError(log::cat("physics: the configuration gives a non-finite wrench at t = ", t,
                                  " s (jet model, aggregation and effects together are not usable)"));
    }
}

// 2-4. The stand's response, its chips (or a flying sufferer's residual), the tare and the recorded
// wrench: the recording chain after the air, into the flight; the force on the sufferer into truth.
void record(const PhysicsConfig& c, const FlyingSufferer& o, ChainInput in, const RecordingChain& chain, Rng& rng,
            flight::Flight& f) {
    const bool flying = o.enabled;
    ChipSampler chips(c.stand, rng);
    RateSampler residual(o.rate_hz, c.stand.noise_n, rng);
    in.tare_s = flying ? 0.0 : c.stand.tare_s;  // a residual is no stand's: no tare
    in.moments_measured = !flying;
    Samples s = chain.record(std::move(in), flying ? static_cast<Sampler&>(residual) : chips);
    for (std::size_t i = 0; i < s.stamps.size(); ++i) f.wrench.push_back({s.stamps[i], s.w[i]});
}

// The flight's bodies in meta.json: the sufferer, then v1..vK; returns the neighbours' indices.
std::vector<std::uint16_t> describe_bodies(flight::Flight& f, const PhysicsConfig& c, const Formation& formation,
                                           bool flying) {
    f.meta.sufferer = flight::kSufferer;
    f.meta.formation = formation.meta_name;
    f.meta.stand_height_m = c.stand.height_m;
    if (flying) {
        f.meta.stand_height_m.reset();
        f.meta.wrench_source = flight::WrenchSource::residual;
        f.meta.moments_measured = false;
    }
    f.meta.extra_json = R"({"generator":"dw-sim fly"})";
    f.body_index(flight::kSufferer);
    f.meta.vehicles[flight::kSufferer] = c.sufferer.vehicle;
    std::vector<std::uint16_t> bodies;
    for (std::size_t j = 0; j < formation.offsets.size(); ++j) {
        const std::string name = "v" + std::to_string(j + 1);
        f.meta.neighbours.push_back(name);
        f.meta.vehicles[name] = c.neighbour;
        bodies.push_back(f.body_index(name));
    }
    return bodies;
}

// The flying vehicles and their jets' turbulence.
struct Fleet {
    std::vector<SimVehicle> vehicles;
    std::vector<Turbulence> turbulence;
    std::vector<Producer> producers;  // their jets at the current step

    // Steps every vehicle towards the reference plus its formation offset (not at step 0) and
    // evaluates its jet; a vehicle that diverges is an error in the configuration.
    void step(const Formation& formation, const Setpoint& ref, std::size_t n, double t, double dt,
              const PhysicsConfig& c, const WrenchModel& model) {
        for (std::size_t j = 0; j < vehicles.size(); ++j) {
            Setpoint sp = ref;
            sp.position += formation.offsets[j];
            if (n > 0) vehicles[j].step(sp, dt);
            const VehicleState& s = vehicles[j].state();
            if (!((s.position - sp.position).norm() <= kDivergence_m)) {
                throw InputError(log::cat("physics: simulated vehicle v", j + 1, " diverged at t = ", t,
                                          " s (dynamics too stiff for dynamics.rate_hz ", c.dynamics.rate_hz, " Hz?)"));
            }
            producers[j] = model.producer(s.position, s.velocity);
            producers[j].axis = vehicles[j].jet_axis();
            if (c.turbulence.enabled) turbulence[j].step(dt, producers[j]);
        }
    }
};

// Throws dw::InputError naming the first option of a flying sufferer outside its range.
void check(const FlyingSufferer& o) {
    const std::pair<const char*, std::pair<double, Range>> checks[] = {{"sway_n_m", {o.sway_n_m, kSwayRange}},
                                                                       {"sway_d_m", {o.sway_d_m, kSwayRange}},
                                                                       {"period_n_s", {o.period_n_s, kSwayPeriodRange}},
                                                                       {"period_d_s", {o.period_d_s, kSwayPeriodRange}},
                                                                       {"rate_hz", {o.rate_hz, kResidualRateRange}}};
    for (const auto& [name, v] : checks)
        if (!v.second.contains(v.first))
            throw InputError(log::cat("flying sufferer: ", name, " ", v.first, " is not in ", v.second.describe()));
}

// The fleet at the reference's start, each vehicle with its own streams split off `master`.
Fleet launch(const PhysicsConfig& c, const Formation& formation, const ReferenceTrajectory& reference,
             std::uint64_t seed, Rng& master) {
    Fleet fleet;
    fleet.producers.resize(formation.offsets.size());
    for (std::size_t j = 0; j < formation.offsets.size(); ++j) {
        fleet.vehicles.emplace_back(c.dynamics, c.gravity_m_s2, reference.at(0).position + formation.offsets[j],
                                    master.split());
        fleet.turbulence.emplace_back(c.turbulence, master.split(), Rng(seed ^ (kBuffetSeed * (j + 1))));
    }
    return fleet;
}

// The sufferer: held by the stand, or flying its sway about the stand's point.
class Sufferer {
public:
    Sufferer(const PhysicsConfig& c, const FlyingSufferer& o, Rng& master)
        : c_(c), o_(o), home_(sufferer_on_stand(c.stand)) {
        if (!o.enabled) return;
        check(o);
        vehicle_.emplace(c.dynamics, c.gravity_m_s2, home_, master.split());
    }
    void step(std::size_t n, double t, double dt) {
        if (vehicle_ && n > 0) vehicle_->step(sway(t), dt);
    }
    Vec3 position() const { return vehicle_ ? vehicle_->state().position : home_; }
    Eigen::Quaterniond orientation() const {
        return vehicle_ ? vehicle_->state().orientation : Eigen::Quaterniond::Identity();
    }
    bool flying() const { return vehicle_.has_value(); }
    // As the chain's stage sufferer sees it (its own forces: a flying sufferer's only).
    SuffererState state() const {
        const auto& s = vehicle_->state();
        return sufferer_state(c_, c_.sufferer.vehicle, s.position, s.velocity);
    }

private:
    Setpoint sway(double t) const {
        const double wn = 2 * M_PI / o_.period_n_s, wd = 2 * M_PI / o_.period_d_s;
        const Vec3 phase(std::sin(wn * t), 0, std::sin(wd * t)), rate(wn * std::cos(wn * t), 0, wd * std::cos(wd * t));
        const Vec3 amplitude(o_.sway_n_m, 0, o_.sway_d_m);
        Setpoint sp;
        sp.position = home_ + amplitude.cwiseProduct(phase);
        sp.velocity = amplitude.cwiseProduct(rate);
        sp.acceleration = -amplitude.cwiseProduct(Vec3(wn * wn, 0, wd * wd)).cwiseProduct(phase);
        return sp;
    }
    const PhysicsConfig& c_;
    FlyingSufferer o_;
    Vec3 home_;
    std::optional<SimVehicle> vehicle_;
};

}  // namespace

SimResult simulate_flight(const PhysicsConfig& c, const FlyOptions& o) {
    const Formation formation = make_formation(o.formation);
    GridOptions grid = o.grid;
    grid.stand_height_m = c.stand.height_m;
    const ReferenceTrajectory reference(grid);
    const WrenchModel model(c);
    const RecordingChain chain(c.effects);

    Rng master(o.seed);
    const std::size_t k = formation.offsets.size();
    Fleet fleet = launch(c, formation, reference, o.seed, master);
    Rng mocap_rng = master.split();
    Rng stand_rng = master.split();

    SimResult out;
    flight::Flight& f = out.flight;
    const std::vector<std::uint16_t> bodies = describe_bodies(f, c, formation, o.flying_sufferer.enabled);
    const std::uint16_t sufferer_body = f.body_index(flight::kSufferer);
    Sufferer sufferer(c, o.flying_sufferer, master);  // after the other streams: theirs stay as they were

    // 1. Fly, and evaluate the true wrench at every integration step.
    const double dt = 1.0 / c.dynamics.rate_hz;
    const auto steps = static_cast<std::size_t>(std::ceil(reference.duration() / dt)) + 1;
    const double mocap_dt = 1.0 / c.mocap.rate_hz;
    double next_mocap = 0;
    ChainInput in;  // the air on the sufferer at every step, for the recording chain
    in.t.reserve(steps);
    in.force.reserve(steps);
    std::vector<SuffererState> states;  // a flying sufferer's, at every step
    auto add_pose = [&](double t, std::uint16_t body, const Vec3& p, const Eigen::Quaterniond& q, const Vec3& offset) {
        flight::PoseSample s;
        s.t = t;
        s.body = body;
        for (int i = 0; i < 3; ++i)
            s.p[static_cast<std::size_t>(i)] = p[i] + offset[i] + c.mocap.noise_m * mocap_rng.normal();
        s.q = {q.w(), q.x(), q.y(), q.z()};
        f.poses.push_back(s);
    };
    const Vec3 pos_offset = chain.position_error_m();  // the motion capture's, on the neighbours
    for (std::size_t n = 0; n < steps; ++n) {
        const double t = static_cast<double>(n) * dt;
        fleet.step(formation, reference.at(t), n, t, dt, c, model);
        sufferer.step(n, t, dt);
        in.t.push_back(t);
        in.force.push_back(to_wrench6(model.evaluate(sufferer.position(), fleet.producers)));
        check_finite(t, in.force.back());
        if (sufferer.flying()) states.push_back(sufferer.state());
        if (t + 1e-9 >= next_mocap) {
            add_pose(t, sufferer_body, sufferer.position(), sufferer.orientation(), Vec3::Zero());
            for (std::size_t j = 0; j < k; ++j) {
                const VehicleState& s = fleet.vehicles[j].state();
                add_pose(t, bodies[j], s.position, s.orientation, pos_offset);
            }
            next_mocap += mocap_dt;
        }
        if (n % 4096 == 0) {
            throw_if_stopped(o.stop, "the simulation");
            if (o.progress) o.progress(0.9 * static_cast<double>(n) / static_cast<double>(steps));
        }
    }

    // 2-4. The stand's response, its chips, the tare and the recorded wrench (or the residual).
    out.truth_t = in.t;
    if (sufferer.flying()) in.sufferer = [&states](std::size_t i) { return states[i]; };
    in.felt = [&out](const RecordedWrench& w) {
        for (std::size_t i = 0; i < w.size(); ++i) check_finite(out.truth_t[i], w[i]);
        out.truth = w;
    };
    record(c, o.flying_sufferer, std::move(in), chain, stand_rng, f);

    std::vector<flight::Leg> legs;
    for (const auto& l : reference.legs()) legs.push_back({l.index, l.t_start, l.t_end});
    f.legs = std::move(legs);
    if (o.progress) o.progress(1.0);
    return out;
}

}  // namespace dw::physics
