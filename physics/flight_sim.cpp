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

// The wrench series at the base rate, read between samples by linear interpolation.
Wrench interpolate(const std::vector<Wrench>& w, double t, double dt) {
    const double x = t / dt;
    if (x <= 0) return w.front();
    const auto i = static_cast<std::size_t>(x);
    if (i + 1 >= w.size()) return w.back();
    const double a = x - static_cast<double>(i);
    return (1 - a) * w[i] + a * w[i + 1];
}

// 2. The stand's response: the recording chain's sensor stage on the true wrench.
std::vector<Wrench> felt_wrench(const std::vector<Wrench>& truth, const std::vector<double>& t,
                                const RecordingChain& chain) {
    RecordedWrench series;
    for (const auto& w : truth) series.push_back(to_wrench6(w));
    chain.sensor(t, series);
    std::vector<Wrench> felt;
    for (const auto& w : series) felt.push_back(to_wrench(w));
    return felt;
}

using Counts = Eigen::Matrix<double, kCells, 1>;
struct StandFrames {  // what the agent publishes: every chip's latest counts when chip 0 converts
    std::vector<double> t;
    std::vector<Counts> counts;
};

// 3. Eight HX711s on their own oscillators, each converting its cell's force.
StandFrames convert_on_chips(const PhysicsConfig& c, const StandModel& stand, const std::vector<Wrench>& felt,
                             double dt, double end, Rng& stand_rng) {
    struct Chip {
        double period, phase, offset;
        std::vector<double> t;
        std::vector<std::int32_t> counts;
    };
    std::array<Chip, kCells> chips;
    for (int ci = 0; ci < kCells; ++ci) {
        Chip& chip = chips[static_cast<std::size_t>(ci)];
        chip.period = 1.0 / (c.stand.rate_hz * (1.0 + c.stand.rate_skew * (2 * stand_rng.uniform() - 1)));
        chip.phase = chip.period * stand_rng.uniform();
        chip.offset = c.stand.offset_sigma_counts * stand_rng.normal();
        for (double t = chip.phase; t <= end; t += chip.period) {
            const auto cells = stand.wrench_to_cells(interpolate(felt, t, dt));
            const double force = cells[ci] + c.stand.noise_n * stand_rng.normal();
            chip.t.push_back(t);
            chip.counts.push_back(StandModel::to_counts(force, chip.offset, c.stand.counts_per_newton));
        }
    }
    std::array<std::size_t, kCells> latest{};
    StandFrames out;
    for (std::size_t i = 0; i < chips[0].t.size(); ++i) {
        const double t = chips[0].t[i];
        Counts counts;
        bool complete = true;
        for (std::size_t ci = 0; ci < kCells; ++ci) {
            while (latest[ci] + 1 < chips[ci].t.size() && chips[ci].t[latest[ci] + 1] <= t) ++latest[ci];
            if (chips[ci].t.empty() || chips[ci].t[latest[ci]] > t) complete = false;
            else counts[static_cast<Eigen::Index>(ci)] = chips[ci].counts[latest[ci]];
        }
        if (!complete) continue;
        out.t.push_back(t);
        out.counts.push_back(counts);
    }
    return out;
}

// The recorded wrench at its stamps, after the chain's recording stage, into the flight.
void write_recording(const RecordingChain& chain, const std::vector<double>& stamps, RecordedWrench& recorded,
                     flight::Flight& f) {
    chain.recording(stamps, recorded);
    for (std::size_t i = 0; i < stamps.size(); ++i) f.wrench.push_back({stamps[i], recorded[i]});
}

// 4. Tare (the mean of the first tare_s: neighbours far away, sufferer at hover thrust), the
// calibrated wrench, then the recording chain's calibration, clock and recording stages.
void record_wrench(const PhysicsConfig& c, const StandModel& stand, const StandFrames& frames,
                   const RecordingChain& chain, flight::Flight& f) {
    Counts zero = Counts::Zero();
    int tare_n = 0;
    for (std::size_t i = 0; i < frames.t.size() && frames.t[i] < frames.t.front() + c.stand.tare_s; ++i, ++tare_n)
        zero += frames.counts[i];
    zero /= std::max(tare_n, 1);
    const double delay = chain.clock_delay_s();
    std::vector<double> stamps;
    RecordedWrench recorded;
    for (std::size_t i = 0; i < frames.t.size(); ++i) {
        Wrench6 x = to_wrench6(stand.cells_to_wrench() * ((frames.counts[i] - zero) / c.stand.counts_per_newton));
        chain.calibration(x);
        stamps.push_back(frames.t[i] + delay);
        recorded.push_back(x);
    }
    write_recording(chain, stamps, recorded, f);
}

// 3-4 for a flying sufferer: its residual, the felt forces at the residual's rate with noise (no
// moments, no tare), through the chain's calibration, clock and recording stages.
void record_residual(const PhysicsConfig& c, const FlyingSufferer& o, const std::vector<Wrench>& felt, double dt,
                     double end, const RecordingChain& chain, Rng& rng, flight::Flight& f) {
    const double delay = chain.clock_delay_s();
    std::vector<double> stamps;
    RecordedWrench recorded;
    for (std::size_t i = 0; static_cast<double>(i) / o.rate_hz <= end; ++i) {
        const double t = static_cast<double>(i) / o.rate_hz;
        Wrench6 x = to_wrench6(interpolate(felt, t, dt));
        for (std::size_t a = 0; a < 3; ++a) x[a] += c.stand.noise_n * rng.normal();
        chain.calibration(x);
        for (std::size_t a = 3; a < 6; ++a) x[a] = 0;  // moments_measured: false
        stamps.push_back(t + delay);
        recorded.push_back(x);
    }
    write_recording(chain, stamps, recorded, f);
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
    // What its own flight adds to the air's wrench (the chain's stage sufferer); nothing on the stand.
    Wrench own_force(const RecordingChain& chain) const {
        if (!vehicle_) return Wrench::Zero();
        const auto& s = vehicle_->state();
        return to_wrench(chain.sufferer_force(sufferer_state(c_, c_.sufferer.vehicle, s.position, s.velocity)));
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
    const StandModel stand(c.stand);
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
    out.truth_t.reserve(steps);
    out.truth.reserve(steps);
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
        out.truth_t.push_back(t);
        out.truth.push_back(model.evaluate(sufferer.position(), fleet.producers) + sufferer.own_force(chain));
        if (!out.truth.back().allFinite()) {
            throw InputError(log::cat("physics: the configuration gives a non-finite wrench at t = ", t,
                                      " s (jet model, aggregation and effects together are not usable)"));
        }
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
    const std::vector<Wrench> felt = felt_wrench(out.truth, out.truth_t, chain);
    if (o.flying_sufferer.enabled)
        record_residual(c, o.flying_sufferer, felt, dt, out.truth_t.back(), chain, stand_rng, f);
    else record_wrench(c, stand, convert_on_chips(c, stand, felt, dt, out.truth_t.back(), stand_rng), chain, f);

    std::vector<flight::Leg> legs;
    for (const auto& l : reference.legs()) legs.push_back({l.index, l.t_start, l.t_end});
    f.legs = std::move(legs);
    if (o.progress) o.progress(1.0);
    return out;
}

}  // namespace dw::physics
