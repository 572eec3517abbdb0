#pragma once
// Every lab message as JSON, field names exactly as in the IDL: for exports (CSV columns are the
// flattened JSON paths) and for comparing with what independent decoders read.
#include <nlohmann/json.hpp>

#include "dds/topics.hpp"

namespace dw::dds {

nlohmann::json to_json(const msg::Time& m);
nlohmann::json to_json(const msg::Header& m);
nlohmann::json to_json(const msg::Vector3& m);
nlohmann::json to_json(const msg::Quaternion& m);
nlohmann::json to_json(const msg::WrenchStamped& m);
nlohmann::json to_json(const msg::LoadCellFrame& m);
nlohmann::json to_json(const msg::StandStatus& m);
nlohmann::json to_json(const msg::RigidBody& m);
nlohmann::json to_json(const msg::MocapFrame& m);
nlohmann::json to_json(const msg::VehicleState& m);
nlohmann::json to_json(const msg::VehicleSetpoint& m);
nlohmann::json to_json(const msg::Leg& m);
nlohmann::json to_json(const msg::ExperimentPlan& m);
nlohmann::json to_json(const msg::ExperimentCommand& m);
nlohmann::json to_json(const msg::ExperimentState& m);
nlohmann::json to_json(const msg::WrenchPrediction& m);
nlohmann::json to_json(const msg::TopicRate& m);
nlohmann::json to_json(const msg::ProcessStatus& m);
nlohmann::json to_json(const msg::ClockProbe& m);

// Flattens nested objects and arrays into "a.b", "a[2].c" keys, in document order.
std::vector<std::pair<std::string, nlohmann::json>> flatten(const nlohmann::json& j);

}  // namespace dw::dds
