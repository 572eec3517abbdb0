#pragma once
// Neural-Swarm (aerorobotics/neural-swarm) Crazyflie logs: the CSV files and the binary micro-SD
// logs they were made from (../shared/data/neural-swarm/README.md gives both formats, the
// vehicles and the residual force Fa). Each vehicle logs on its own clock; the files of a trial are
// aligned at their first samples, as the authors do.
#include <array>
#include <cstdint>
#include <stop_token>
#include <string>
#include <vector>

#include "importer/importer.hpp"

namespace dw::importer {

// One vehicle's log in the source's own frame (world z up, body x forward y left z up) and SI
// units, time from the log's first sample.
struct VehicleLog {
    std::string name;  // cf50, cf101, ... (from the file name)
    std::string file;
    std::vector<double> t_s;
    std::vector<std::array<double, 3>> position_m;
    std::vector<std::array<double, 3>> accel_mps2;  // world frame, gravity included
    std::vector<std::array<double, 4>> quat_xyzw;   // body -> world, scalar last
    std::vector<std::array<double, 4>> pwm;         // 0..1
    std::vector<double> vbat_v;
    std::vector<double> faz_g;       // binary logs with ctrlFa.Faz: the onboard network's Fa_z [gram-force, z up]
    std::size_t damaged_blocks = 0;  // binary: blocks whose checksum failed, skipped
    // Where each sample is in the file: its line (CSV) or its record's first byte (binary), so that
    // what is derived from a sample (the residual force) is refused where the sample was read.
    bool binary = false;
    std::vector<std::size_t> origin;
    std::string where(std::size_t sample) const;  // "file:line" or "file: byte N"
};

// The binary logs' field of the authors' onboard interaction network's Fa_z (gram-force, z up).
inline constexpr const char* kFazField = "ctrlFa.Faz";

// Reads a CSV log (`*.csv`) or a binary log (no extension). Throws dw::InputError with the file,
// the line or byte offset and the problem (also past `max_samples`, what is left of the trial's
// kMaxTrialSamples); dw::Stopped when `stop` is requested.
VehicleLog read_neural_swarm_log(const std::string& path, const std::stop_token& stop = {},
                                 std::size_t max_samples = kMaxTrialSamples);

// A Crazyflie of the collection: mass, arm, propeller and the PWM/voltage thrust map.
struct CrazyflieType {
    std::string kind;  // small (Crazyflie 2.1) or large (parrot frame)
    double mass_kg;
    double arm_m;                    // centre to motor (sysId)
    double prop_radius_m;            // not stated by the authors: see docs/REAL.md
    double ground_z_m;               // z below which it touches the ground
    std::array<double, 5> thrust_g;  // c00 c10 c01 c20 c11: grams-force per motor of (pwm, vbat/4.2)
};
// Throws dw::InputError for a vehicle name the collection does not describe.
const CrazyflieType& crazyflie_type(const std::string& vehicle);

// The collection a trial's logs came from: the source keeps each log as
// <collection>/<experiment>/<log> (data/training/datacollection21_06_16_2020/swap_ss/cf50_01), so it
// is the folder above the log's own ("(unknown collection)" for a log less than two folders deep).
// Throws dw::InputError naming two logs of different collections.
std::string collection_of(const std::vector<std::string>& log_files);

// One trial of a collection folder: its name (<experiment>_<trial>, e.g. swap_ss_01) and one log
// per vehicle (the binary log where there is one, else the CSV made from it), in name order.
struct CollectionTrial {
    std::string name;
    std::vector<std::string> logs;
};
// Every trial under `dir`, laid out as the source keeps it: <dir>/<experiment>/<vehicle>_<trial>[.csv].
// Files not named so are left out. Throws dw::InputError when `dir` is not a folder or holds no trial.
std::vector<CollectionTrial> collection_trials(const std::string& dir);

// The importer: `dw-import neural-swarm LOG...`.
const Importer& neural_swarm_importer();

}  // namespace dw::importer
