#pragma once
// Deterministic samples of every lab message type: sample i of a type is always the same, so a
// receiver can check that what arrived is exactly what was sent (make_sample<T>(seq) == sample).
// Every field is set, sequences and strings included, so a lost or mangled field shows.
#include <cstdint>
#include <string>

#include "dds/topics.hpp"

namespace dw::probe {

// The run id that marks a probe sample (real lab traffic carries its experiment's run id).
inline constexpr const char* kProbeRunId = "probe";

void fill(msg::WrenchStamped& m, std::uint64_t i);
void fill(msg::LoadCellFrame& m, std::uint64_t i);
void fill(msg::StandStatus& m, std::uint64_t i);
void fill(msg::MocapFrame& m, std::uint64_t i);
void fill(msg::VehicleState& m, std::uint64_t i);
void fill(msg::VehicleSetpoint& m, std::uint64_t i);
void fill(msg::VehicleCommandSent& m, std::uint64_t i);
void fill(msg::ExperimentPlan& m, std::uint64_t i);
void fill(msg::ExperimentCommand& m, std::uint64_t i);
void fill(msg::ExperimentState& m, std::uint64_t i);
void fill(msg::WrenchPrediction& m, std::uint64_t i);
void fill(msg::ProcessStatus& m, std::uint64_t i);
void fill(msg::ClockProbe& m, std::uint64_t i);

// Sample i: header.seq = i, a stamp derived from i, run id kProbeRunId, the body from fill().
template <class T>
T make_sample(std::uint64_t i) {
    T m;
    fill(m, i);
    m.header().seq(i);
    m.header().stamp().sec(static_cast<std::int32_t>(1'700'000'000 + i / 100));
    m.header().stamp().nanosec(static_cast<std::uint32_t>((i % 100) * 10'000'000));
    m.header().run_id(kProbeRunId);
    return m;
}

// One line a person can read: the fields that matter of each type.
std::string summary(const msg::WrenchStamped& m);
std::string summary(const msg::LoadCellFrame& m);
std::string summary(const msg::StandStatus& m);
std::string summary(const msg::MocapFrame& m);
std::string summary(const msg::VehicleState& m);
std::string summary(const msg::VehicleSetpoint& m);
std::string summary(const msg::VehicleCommandSent& m);
std::string summary(const msg::ExperimentPlan& m);
std::string summary(const msg::ExperimentCommand& m);
std::string summary(const msg::ExperimentState& m);
std::string summary(const msg::WrenchPrediction& m);
std::string summary(const msg::ProcessStatus& m);
std::string summary(const msg::ClockProbe& m);

}  // namespace dw::probe
