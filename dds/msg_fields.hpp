#pragma once
// Every lab message's fields in IDL order, named exactly as in the IDL: written once here and
// visited by the JSON conversion (dds/msg_json.hpp) and the CSV export (recordings). A visitor is
// called v("name", value) for each field; a value is a number, bool, enum, string, another
// message (IsMessage) or a sequence/array of those (IsSequence).
#include <cmath>
#include <concepts>
#include <type_traits>
#include <string>

#include "dds/topics.hpp"

namespace dw::dds {

template <class V>
void fields(const msg::Time& m, V& v) {
    v("sec", m.sec()), v("nanosec", m.nanosec());
}
template <class V>
void fields(const msg::Header& m, V& v) {
    v("stamp", m.stamp()), v("seq", m.seq()), v("run_id", m.run_id());
}
template <class V>
void fields(const msg::Vector3& m, V& v) {
    v("x", m.x()), v("y", m.y()), v("z", m.z());
}
template <class V>
void fields(const msg::Quaternion& m, V& v) {
    v("w", m.w()), v("x", m.x()), v("y", m.y()), v("z", m.z());
}
template <class V>
void fields(const msg::WrenchStamped& m, V& v) {
    v("header", m.header()), v("force_n", m.force_n()), v("torque_nm", m.torque_nm()), v("tared", m.tared());
}
template <class V>
void fields(const msg::LoadCellFrame& m, V& v) {
    v("header", m.header()), v("counts", m.counts()), v("status", m.status()),
        v("cell_time_offset_s", m.cell_time_offset_s()), v("gain", m.gain());
}
template <class V>
void fields(const msg::StandStatus& m, V& v) {
    v("header", m.header()), v("state", m.state()), v("fault_cells", m.fault_cells()), v("message", m.message()),
        v("sample_rate_hz", m.sample_rate_hz()), v("samples_published", m.samples_published()),
        v("samples_discarded", m.samples_discarded()), v("spikes_rejected", m.spikes_rejected()),
        v("tare_offset_counts", m.tare_offset_counts()), v("last_tare", m.last_tare()),
        v("pipeline_delay_s", m.pipeline_delay_s());
}
template <class V>
void fields(const msg::RigidBody& m, V& v) {
    v("name", m.name()), v("id", m.id()), v("position_m", m.position_m()), v("orientation", m.orientation()),
        v("tracking_valid", m.tracking_valid()), v("residual_m", m.residual_m());
}
template <class V>
void fields(const msg::MocapFrame& m, V& v) {
    v("header", m.header()), v("frame_number", m.frame_number()), v("camera_mid_exposure", m.camera_mid_exposure()),
        v("transmit", m.transmit()), v("receive", m.receive()), v("timestamp_mode", m.timestamp_mode()),
        v("dropped_frames", m.dropped_frames()), v("bodies", m.bodies()), v("pose_source", m.pose_source());
}
template <class V>
void fields(const msg::VehicleState& m, V& v) {
    v("header", m.header()), v("vehicle_id", m.vehicle_id()), v("position_m", m.position_m()),
        v("velocity_mps", m.velocity_mps()), v("orientation", m.orientation()), v("tracking_valid", m.tracking_valid()),
        v("staleness_s", m.staleness_s()), v("armed", m.armed()), v("airborne", m.airborne());
}
template <class V>
void fields(const msg::VehicleSetpoint& m, V& v) {
    v("header", m.header()), v("vehicle_id", m.vehicle_id()), v("position_m", m.position_m()),
        v("velocity_mps", m.velocity_mps()), v("acceleration_mps2", m.acceleration_mps2()), v("yaw_rad", m.yaw_rad());
}
template <class V>
void fields(const msg::VehicleCommandSent& m, V& v) {
    v("header", m.header()), v("vehicle_id", m.vehicle_id()), v("command", m.command()), v("name", m.name()),
        v("param1", m.param1()), v("param2", m.param2()), v("target_system", m.target_system());
}
template <class V>
void fields(const msg::Leg& m, V& v) {
    v("index", m.index()), v("start_m", m.start_m()), v("end_m", m.end_m()), v("speed_mps", m.speed_mps()),
        v("relative_altitude_m", m.relative_altitude_m());
}
template <class V>
void fields(const msg::ExperimentPlan& m, V& v) {
    v("header", m.header()), v("name", m.name()), v("formation", m.formation()), v("vehicles", m.vehicles()),
        v("offsets_m", m.offsets_m()), v("legs", m.legs()), v("document", m.document());
}
template <class V>
void fields(const msg::ExperimentCommand& m, V& v) {
    v("header", m.header()), v("kind", m.kind()), v("issuer", m.issuer()), v("reason", m.reason());
}
template <class V>
void fields(const msg::ExperimentState& m, V& v) {
    v("header", m.header()), v("phase", m.phase()), v("leg_index", m.leg_index()), v("leg_count", m.leg_count()),
        v("progress", m.progress()), v("eta_s", m.eta_s()), v("message", m.message());
}
template <class V>
void fields(const msg::WrenchPrediction& m, V& v) {
    v("header", m.header()), v("model_name", m.model_name()), v("force_n", m.force_n()), v("torque_nm", m.torque_nm()),
        v("input_age_s", m.input_age_s()), v("f_d_interval_n", m.f_d_interval_n());
}
template <class V>
void fields(const msg::TopicRate& m, V& v) {
    v("topic", m.topic()), v("outgoing", m.outgoing()), v("rate_hz", m.rate_hz()), v("samples", m.samples()),
        v("lost", m.lost());
}
template <class V>
void fields(const msg::ProcessStatus& m, V& v) {
    v("header", m.header()), v("process", m.process()), v("host", m.host()), v("pid", m.pid()), v("state", m.state()),
        v("period_s", m.period_s()), v("rates", m.rates()), v("error_count", m.error_count()),
        v("message", m.message()), v("clock_offset_s", m.clock_offset_s()),
        v("clock_uncertainty_s", m.clock_uncertainty_s());
}
template <class V>
void fields(const msg::ClockProbe& m, V& v) {
    v("header", m.header()), v("process", m.process()), v("probe", m.probe()),
        v("reference_receive", m.reference_receive()), v("reference_send", m.reference_send());
}

namespace detail {
struct AnyVisitor {
    template <class T>
    void operator()(const char*, const T&) {}
};
}  // namespace detail

// A lab message (it has fields above), as opposed to a value or a sequence.
template <class T>
concept IsMessage = requires(const T& m, detail::AnyVisitor& v) {
    fields(m, v);
};
// A sequence<> or an array of the IDL (std::vector, std::array); a string is a value.
template <class T>
concept IsSequence = !std::same_as<T, std::string> && requires(const T& s) {
    s.begin();
    s.size();
};

namespace detail {
struct FiniteCheck {
    bool ok = true;
    template <class T>
    void operator()(const char*, const T& v) {
        add(v);
    }
    template <class T>
    void add(const T& v) {
        if constexpr (IsMessage<T>) {
            fields(v, *this);
        } else if constexpr (IsSequence<T>) {
            for (const auto& e : v) add(e);
        } else if constexpr (std::is_floating_point_v<T>) {
            ok = ok && std::isfinite(v);
        }
    }
};
}  // namespace detail

// Whether every floating-point field of a lab message (nested, in sequences) is finite.
template <class T>
bool all_finite(const T& m) {
    detail::FiniteCheck c;
    c.add(m);
    return c.ok;
}

}  // namespace dw::dds
