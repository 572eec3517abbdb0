#include "dds/msg_json.hpp"

namespace dw::dds {
using nlohmann::json;

namespace {
template <class Seq>
json array_of(const Seq& seq) {
    json a = json::array();
    for (const auto& v : seq) {
        if constexpr (std::is_arithmetic_v<std::decay_t<decltype(v)>> || std::is_enum_v<std::decay_t<decltype(v)>> ||
                      std::is_same_v<std::decay_t<decltype(v)>, std::string>) {
            if constexpr (std::is_enum_v<std::decay_t<decltype(v)>>) a.push_back(static_cast<std::int64_t>(v));
            else a.push_back(v);
        } else {
            a.push_back(to_json(v));
        }
    }
    return a;
}
template <class E>
std::int64_t e(E v) { return static_cast<std::int64_t>(v); }
}  // namespace

json to_json(const msg::Time& m) { return json{{"sec", m.sec()}, {"nanosec", m.nanosec()}}; }
json to_json(const msg::Header& m) { return json{{"stamp", to_json(m.stamp())}, {"seq", m.seq()}, {"run_id", m.run_id()}}; }
json to_json(const msg::Vector3& m) { return json{{"x", m.x()}, {"y", m.y()}, {"z", m.z()}}; }
json to_json(const msg::Quaternion& m) { return json{{"w", m.w()}, {"x", m.x()}, {"y", m.y()}, {"z", m.z()}}; }
json to_json(const msg::WrenchStamped& m) {
    return json{{"header", to_json(m.header())}, {"force_n", to_json(m.force_n())}, {"torque_nm", to_json(m.torque_nm())},
                {"tared", m.tared()}};
}
json to_json(const msg::LoadCellFrame& m) {
    return json{{"header", to_json(m.header())}, {"counts", array_of(m.counts())}, {"status", array_of(m.status())},
                {"cell_time_offset_s", array_of(m.cell_time_offset_s())}, {"gain", m.gain()}};
}
json to_json(const msg::StandStatus& m) {
    return json{{"header", to_json(m.header())}, {"state", e(m.state())}, {"fault_cells", array_of(m.fault_cells())},
                {"message", m.message()}, {"sample_rate_hz", m.sample_rate_hz()},
                {"samples_published", m.samples_published()}, {"samples_discarded", m.samples_discarded()},
                {"spikes_rejected", m.spikes_rejected()}, {"tare_offset_counts", array_of(m.tare_offset_counts())},
                {"last_tare", to_json(m.last_tare())}};
}
json to_json(const msg::RigidBody& m) {
    return json{{"name", m.name()}, {"id", m.id()}, {"position_m", to_json(m.position_m())},
                {"orientation", to_json(m.orientation())}, {"tracking_valid", m.tracking_valid()},
                {"residual_m", m.residual_m()}};
}
json to_json(const msg::MocapFrame& m) {
    return json{{"header", to_json(m.header())}, {"frame_number", m.frame_number()},
                {"camera_mid_exposure", to_json(m.camera_mid_exposure())}, {"transmit", to_json(m.transmit())},
                {"receive", to_json(m.receive())}, {"timestamp_mode", e(m.timestamp_mode())},
                {"dropped_frames", m.dropped_frames()}, {"bodies", array_of(m.bodies())}};
}
json to_json(const msg::VehicleState& m) {
    return json{{"header", to_json(m.header())}, {"vehicle_id", m.vehicle_id()}, {"position_m", to_json(m.position_m())},
                {"velocity_mps", to_json(m.velocity_mps())}, {"orientation", to_json(m.orientation())},
                {"tracking_valid", m.tracking_valid()}, {"staleness_s", m.staleness_s()}, {"armed", m.armed()},
                {"airborne", m.airborne()}};
}
json to_json(const msg::VehicleSetpoint& m) {
    return json{{"header", to_json(m.header())}, {"vehicle_id", m.vehicle_id()}, {"position_m", to_json(m.position_m())},
                {"velocity_mps", to_json(m.velocity_mps())}, {"acceleration_mps2", to_json(m.acceleration_mps2())},
                {"yaw_rad", m.yaw_rad()}};
}
json to_json(const msg::Leg& m) {
    return json{{"index", m.index()}, {"start_m", to_json(m.start_m())}, {"end_m", to_json(m.end_m())},
                {"speed_mps", m.speed_mps()}, {"relative_altitude_m", m.relative_altitude_m()}};
}
json to_json(const msg::ExperimentPlan& m) {
    return json{{"header", to_json(m.header())}, {"name", m.name()}, {"formation", m.formation()},
                {"vehicles", array_of(m.vehicles())}, {"offsets_m", array_of(m.offsets_m())}, {"legs", array_of(m.legs())},
                {"document", m.document()}};
}
json to_json(const msg::ExperimentCommand& m) {
    return json{{"header", to_json(m.header())}, {"kind", e(m.kind())}, {"issuer", m.issuer()}, {"reason", m.reason()}};
}
json to_json(const msg::ExperimentState& m) {
    return json{{"header", to_json(m.header())}, {"phase", e(m.phase())}, {"leg_index", m.leg_index()},
                {"leg_count", m.leg_count()}, {"progress", m.progress()}, {"eta_s", m.eta_s()}, {"message", m.message()}};
}
json to_json(const msg::WrenchPrediction& m) {
    return json{{"header", to_json(m.header())}, {"model_name", m.model_name()}, {"force_n", to_json(m.force_n())},
                {"torque_nm", to_json(m.torque_nm())}, {"input_age_s", m.input_age_s()}};
}
json to_json(const msg::TopicRate& m) {
    return json{{"topic", m.topic()}, {"outgoing", m.outgoing()}, {"rate_hz", m.rate_hz()}, {"samples", m.samples()},
                {"lost", m.lost()}};
}
json to_json(const msg::ProcessStatus& m) {
    return json{{"header", to_json(m.header())}, {"process", m.process()}, {"host", m.host()}, {"pid", m.pid()},
                {"state", e(m.state())}, {"period_s", m.period_s()}, {"rates", array_of(m.rates())},
                {"error_count", m.error_count()}, {"message", m.message()}, {"clock_offset_s", m.clock_offset_s()},
                {"clock_uncertainty_s", m.clock_uncertainty_s()}};
}
json to_json(const msg::ClockProbe& m) {
    return json{{"header", to_json(m.header())}, {"process", m.process()}, {"probe", m.probe()},
                {"reference_receive", to_json(m.reference_receive())}, {"reference_send", to_json(m.reference_send())}};
}

namespace {
void flatten_into(const json& j, const std::string& prefix, std::vector<std::pair<std::string, json>>& out) {
    if (j.is_object()) {
        for (const auto& [k, v] : j.items()) flatten_into(v, prefix.empty() ? k : prefix + "." + k, out);
    } else if (j.is_array()) {
        for (std::size_t i = 0; i < j.size(); ++i) flatten_into(j[i], prefix + "[" + std::to_string(i) + "]", out);
    } else {
        out.emplace_back(prefix, j);
    }
}
}  // namespace

std::vector<std::pair<std::string, json>> flatten(const json& j) {
    std::vector<std::pair<std::string, json>> out;
    flatten_into(j, "", out);
    return out;
}

}  // namespace dw::dds
