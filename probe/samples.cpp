#include "probe/samples.hpp"

#include <cmath>
#include <cstdio>

#include "core/log.hpp"
#include "dds/wire_enums.hpp"
#include "dds/px4.hpp"

namespace dw::probe {
namespace {
double wave(std::uint64_t i, double scale, double phase = 0.0) {
    return scale * std::sin(0.1 * static_cast<double>(i) + phase);
}

msg::Vector3 vec(std::uint64_t i, double scale, double phase = 0.0) {
    msg::Vector3 v;
    v.x(wave(i, scale, phase));
    v.y(wave(i, scale, phase + 2.0));
    v.z(wave(i, scale, phase + 4.0));
    return v;
}

msg::Quaternion quat(std::uint64_t i) {
    const double yaw = 0.05 * static_cast<double>(i % 120);
    msg::Quaternion q;
    q.w(std::cos(yaw / 2));
    q.x(0.0);
    q.y(0.0);
    q.z(std::sin(yaw / 2));
    return q;
}

msg::Time time_of(std::uint64_t i, std::int64_t offset_ns) {
    const std::int64_t t = 1'700'000'000'000'000'000LL + static_cast<std::int64_t>(i) * 5'555'556 + offset_ns;
    msg::Time m;
    m.sec(static_cast<std::int32_t>(t / kNanosPerSecond));
    m.nanosec(static_cast<std::uint32_t>(t % kNanosPerSecond));
    return m;
}

std::string vehicle(std::uint64_t i) { return "v" + std::to_string(i % 3 + 1); }

std::string fmt3(const msg::Vector3& v) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "(%+.3f %+.3f %+.3f)", v.x(), v.y(), v.z());
    return buf;
}
}  // namespace

void fill(msg::WrenchStamped& m, std::uint64_t i) {
    m.force_n(vec(i, 2.0));
    m.torque_nm(vec(i, 0.05, 1.0));
    m.tared(i % 2 == 0);
}

void fill(msg::LoadCellFrame& m, std::uint64_t i) {
    for (std::size_t c = 0; c < 8; ++c) {
        // Sweep the whole 24-bit two's complement range, both saturation codes included.
        const std::int64_t span = 0x7FFFFF;
        const std::int64_t v = static_cast<std::int64_t>((i * 104729 + c * 7919) % (2 * span + 2)) - span - 1;
        m.counts()[c] = static_cast<std::int32_t>(v);
        m.status()[c] = static_cast<msg::CellStatus>((i + c) % 6);
        m.cell_time_offset_s()[c] = 0.0125 * static_cast<double>(c) / 8.0 + 1e-6 * static_cast<double>(i % 7);
    }
    static constexpr std::uint8_t kGains[] = {128, 64, 32};
    m.gain(kGains[i % 3]);
}

void fill(msg::StandStatus& m, std::uint64_t i) {
    m.state(static_cast<msg::StandState>(i % 4));
    m.fault_cells().clear();
    for (std::uint32_t c = 0; c < i % 4; ++c) m.fault_cells().push_back((c * 3 + static_cast<std::uint32_t>(i)) % 8);
    m.message(log::cat("status #", i));
    m.sample_rate_hz(80.0 - 0.01 * static_cast<double>(i % 10));
    m.samples_published(i * 80);
    m.samples_discarded(i / 3);
    m.spikes_rejected(i / 7);
    for (std::size_t c = 0; c < 8; ++c)
        m.tare_offset_counts()[c] = 1000.5 * static_cast<double>(c) - static_cast<double>(i);
    m.last_tare(time_of(i, -kNanosPerSecond));
    m.pipeline_delay_s(i % 2 ? -1.0 : 0.0071);
}

void fill(msg::MocapFrame& m, std::uint64_t i) {
    m.frame_number(100000 + i);
    m.camera_mid_exposure(time_of(i, -4'000'000));
    m.transmit(time_of(i, -1'000'000));
    m.receive(time_of(i, 0));
    m.timestamp_mode(static_cast<msg::MocapTimestampMode>(i % 3));
    m.dropped_frames(static_cast<std::uint32_t>(i / 50));
    m.bodies().clear();
    const std::uint64_t n = 1 + i % 4;  // the sufferer and 0-3 neighbours
    for (std::uint64_t b = 0; b < n; ++b) {
        msg::RigidBody body;
        body.name(b == 0 ? std::string("sufferer") : "v" + std::to_string(b));
        body.id(static_cast<std::int32_t>(b + 1));
        body.position_m(vec(i + b * 10, 1.0));
        body.orientation(quat(i + b));
        body.tracking_valid((i + b) % 5 != 0);
        body.residual_m(0.0001f * static_cast<float>((i + b) % 17));
        m.bodies().push_back(std::move(body));
    }
}

void fill(msg::VehicleState& m, std::uint64_t i) {
    m.vehicle_id(vehicle(i));
    m.position_m(vec(i, 1.0));
    m.velocity_mps(vec(i, 0.5, 0.7));
    m.orientation(quat(i));
    m.tracking_valid(i % 7 != 0);
    m.staleness_s(0.001 * static_cast<double>(i % 9));
    m.armed(i % 2 == 1);
    m.airborne(i % 3 == 1);
}

void fill(msg::VehicleSetpoint& m, std::uint64_t i) {
    m.vehicle_id(vehicle(i));
    m.position_m(vec(i, 1.0, 0.3));
    m.velocity_mps(vec(i, 0.5, 0.9));
    m.acceleration_mps2(vec(i, 0.2, 1.1));
    m.yaw_rad(wave(i, 3.14159));
}

void fill(msg::VehicleCommandSent& m, std::uint64_t i) {
    static constexpr std::uint32_t kCommands[] = {dds::px4::kCmdDoSetMode, dds::px4::kCmdArmDisarm,
                                                  dds::px4::kCmdNavLand};
    m.vehicle_id(vehicle(i));
    m.command(kCommands[i % 3]);
    m.name(dds::px4::command_name(m.command()));
    m.param1(static_cast<float>(i % 2));
    m.param2(static_cast<float>(i % 7));
    m.target_system(static_cast<std::uint32_t>(1 + i % 3));
}

void fill(msg::ExperimentPlan& m, std::uint64_t i) {
    static const char* kFormations[] = {"single", "side_by_side", "leader_follower", "stack", "hybrid", "free"};
    m.name(log::cat("plan-", i));
    m.formation(kFormations[i % 6]);
    m.vehicles().clear();
    m.offsets_m().clear();
    for (std::uint64_t v = 0; v < 1 + i % 3; ++v) {
        m.vehicles().push_back("v" + std::to_string(v + 1));
        m.offsets_m().push_back(vec(i + v, 0.5));
    }
    m.legs().clear();
    for (std::uint32_t l = 0; l < 30 + i % 11; ++l) {
        msg::Leg leg;
        leg.index(l);
        msg::Vector3 a;
        a.x(-1.0 + 2.0 * l / 40.0);
        a.y(-1.0);
        a.z(-1.4 - 0.3 * (l % 3));
        msg::Vector3 b = a;
        b.y(1.0);
        leg.start_m(l % 2 == 0 ? a : b);
        leg.end_m(l % 2 == 0 ? b : a);
        leg.speed_mps(0.5);
        leg.relative_altitude_m(0.3 + 0.5 * (l % 3));
        m.legs().push_back(leg);
    }
    m.document(log::cat("name: plan-", i, "\nformation: ", m.formation(), "\n"));
}

void fill(msg::ExperimentCommand& m, std::uint64_t i) {
    m.kind(static_cast<msg::CommandKind>(i % 6));
    m.issuer("dw-probe");
    m.reason(log::cat("command #", i));
}

void fill(msg::ExperimentState& m, std::uint64_t i) {
    m.phase(static_cast<msg::ExperimentPhase>(i % 8));
    m.leg_index(static_cast<std::int32_t>(i % 40) - 1);
    m.leg_count(36);
    m.progress(static_cast<double>(i % 101) / 100.0);
    m.eta_s(i % 5 == 0 ? -1.0 : 0.5 * static_cast<double>(i));
    m.message(log::cat("state #", i));
}

void fill(msg::WrenchPrediction& m, std::uint64_t i) {
    static const char* kModels[] = {"physics", "naive_linear", "learnt_linear", "deep_sets"};
    m.model_name(kModels[i % 4]);
    m.force_n(vec(i, 2.5, 0.2));
    m.torque_nm(vec(i, 0.04, 1.2));
    m.input_age_s(1e-5 * static_cast<double>(1 + i % 50));
    m.f_d_interval_n(i % 3 == 0 ? 0.0 : 0.02 + 1e-3 * static_cast<double>(i % 7));
}

void fill(msg::ProcessStatus& m, std::uint64_t i) {
    m.process(log::cat("probe-", i % 2));
    m.host("localhost");
    m.pid(static_cast<std::int32_t>(1000 + i));
    m.state(static_cast<msg::ProcessState>(i % 5));
    m.period_s(0.5);
    m.rates().clear();
    for (std::uint64_t r = 0; r < i % 3; ++r) {
        msg::TopicRate rate;
        rate.topic(log::cat("rt/lab/topic", r));
        rate.outgoing(r % 2 == 0);
        rate.rate_hz(80.0 + static_cast<double>(r));
        rate.samples(i * 10 + r);
        rate.lost(r);
        m.rates().push_back(rate);
    }
    m.error_count(i / 4);
    m.message(log::cat("heartbeat #", i));
    m.clock_offset_s(1e-4 * static_cast<double>(i % 7) - 3e-4);
    m.clock_uncertainty_s(i % 4 == 0 ? -1.0 : 5e-5 * static_cast<double>(1 + i % 3));
}

void fill(msg::ClockProbe& m, std::uint64_t i) {
    m.process(log::cat("probe-", i % 2));
    m.probe(i * 3);
    m.reference_receive().sec(static_cast<std::int32_t>(1'700'000'000 + i));
    m.reference_receive().nanosec(static_cast<std::uint32_t>(i % 1000) * 1000);
    m.reference_send().sec(static_cast<std::int32_t>(1'700'000'000 + i));
    m.reference_send().nanosec(static_cast<std::uint32_t>(i % 1000) * 1000 + 20'000);
}

std::string summary(const msg::WrenchStamped& m) {
    return log::cat("force ", fmt3(m.force_n()), " N  torque ", fmt3(m.torque_nm()), " N·m",
                    m.tared() ? "  tared" : "");
}
std::string summary(const msg::LoadCellFrame& m) {
    std::string counts;
    for (auto c : m.counts()) counts += " " + std::to_string(c);
    return log::cat("counts", counts, "  gain ", static_cast<int>(m.gain()));
}
std::string summary(const msg::StandStatus& m) {
    return log::cat(dds::stand_state_name(m.state()), "  ", m.fault_cells().size(), " faulty cells  ",
                    m.sample_rate_hz(), " Hz  '", m.message(), "'");
}
std::string summary(const msg::MocapFrame& m) {
    std::string names;
    for (const auto& b : m.bodies()) names += " " + b.name() + (b.tracking_valid() ? "" : "(lost)");
    return log::cat("frame ", m.frame_number(), "  ", m.bodies().size(), " bodies:", names);
}
std::string summary(const msg::VehicleState& m) {
    return log::cat(m.vehicle_id(), "  pos ", fmt3(m.position_m()), " m  vel ", fmt3(m.velocity_mps()), " m/s");
}
std::string summary(const msg::VehicleSetpoint& m) {
    return log::cat(m.vehicle_id(), "  pos ", fmt3(m.position_m()), " m  yaw ", m.yaw_rad(), " rad");
}
std::string summary(const msg::VehicleCommandSent& m) {
    return log::cat(m.vehicle_id(), "  ", m.name(), " (", m.param1(), ", ", m.param2(), ") to system ",
                    m.target_system());
}
std::string summary(const msg::ExperimentPlan& m) {
    return log::cat("'", m.name(), "'  ", m.formation(), "  ", m.vehicles().size(), " vehicles  ", m.legs().size(),
                    " legs");
}
std::string summary(const msg::ExperimentCommand& m) {
    return log::cat(dds::command_name(m.kind()), " from ", m.issuer(), "  '", m.reason(), "'");
}
std::string summary(const msg::ExperimentState& m) {
    return log::cat(dds::phase_name(m.phase()), "  leg ", m.leg_index(), "/", m.leg_count(), "  ",
                    static_cast<int>(m.progress() * 100), " %");
}
std::string summary(const msg::WrenchPrediction& m) {
    return log::cat(m.model_name(), "  force ", fmt3(m.force_n()), " N  age ", m.input_age_s() * 1e6, " µs");
}
std::string summary(const msg::ProcessStatus& m) {
    return log::cat(m.process(), "@", m.host(), " pid ", m.pid(), "  ", dds::process_state_name(m.state()), "  ",
                    m.rates().size(), " topics  ", m.error_count(), " errors  clock ", m.clock_offset_s() * 1e3, " ms");
}
std::string summary(const msg::ClockProbe& m) {
    return log::cat(m.process(), " probe ", m.probe(), m.reference_send().sec() == 0 ? "  (request)" : "  (answer)");
}

}  // namespace dw::probe
