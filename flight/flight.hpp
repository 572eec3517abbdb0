#pragma once
// Flight folders (downwash-flight/1, ../shared/FLIGHT_FORMAT.md): the plain-file contract every
// tool reads and writes next to MCAP. Reading is all-or-nothing: a file that breaks a rule is
// rejected with dw::InputError naming the file, the line and the problem.
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/files.hpp"
#include "core/numbers.hpp"

namespace dw::flight {

inline constexpr const char* kFormat = "downwash-flight/1";
inline constexpr Range kStandHeightRange{0.1, 10, "m"};
inline constexpr std::array<const char*, 6> kAxes = {"f_n", "f_e", "f_d", "m_roll", "m_pitch", "m_yaw"};
inline constexpr std::size_t kFdAxis = 2;  // f_d's place in kAxes
// A wrench (N, N·m) in kAxes' order, and a value per axis of one (a noise floor, an error).
using Wrench6 = std::array<double, 6>;
using AxisValues = std::array<double, 6>;
// kAxes for messages: "f_n, f_e, f_d, m_roll, m_pitch or m_yaw".
std::string axis_list();
// wrench.csv's columns: t, then kAxes.
std::vector<std::string> wrench_columns();
inline constexpr std::array<const char*, 6> kFormations = {"single", "side_by_side", "leader_follower",
                                                           "stack",  "hybrid",       "free"};

// Every number a flight's files hold lies in a range wide enough for any lab; one outside is damage,
// not a measurement (issue 43). Stamps: Unix-epoch seconds fit.
inline constexpr Range kStampRange{-1e10, 1e10, "s"};
inline constexpr Range kForceRange{-1e4, 1e4, "N"};
inline constexpr Range kMomentRange{-1e4, 1e4, "N·m"};
inline constexpr Range kPositionRange{-1e6, 1e6, "m"};
inline constexpr Range kQuaternionRange{-1.01, 1.01};
// kForceRange for the force axes of kAxes, kMomentRange for the moments.
const Range& axis_range(std::size_t axis);
// The tools walk a flight's span on fixed time grids (the replay, leg and encounter finding): a
// flight holds at least one sample per this many seconds of its span on average, so one stray
// stamp (10^9 s) cannot size them past a small multiple of the input.
inline constexpr double kMaxSpanPerSample_s = 0.1;

// Body names (poses.csv's body column, meta.json's sufferer, neighbours and vehicles): what
// round-trips through the flight format's CSV and JSON, checked where they are read and written.
inline constexpr std::size_t kMaxBodies = 256;  // bodies in one flight (a lab flies a handful)
inline constexpr std::size_t kMaxNameBytes = 64;
// Why `name` cannot name a body, "" when it can: empty, longer than kMaxNameBytes, a comma, a
// double quote, a control byte (CR, LF, ...) or not UTF-8.
std::string body_name_problem(std::string_view name);

// The wrench the air exerts on the sufferer, tared, on the stand clock. N, N·m, NED axes.
struct WrenchSample {
    double t = 0;
    std::array<double, 6> w{};  // f_n f_e f_d m_roll m_pitch m_yaw
};

// One body's pose on the mocap clock. World NED metres; unit quaternion body->world, w first.
struct PoseSample {
    double t = 0;
    std::uint16_t body = 0;  // index into Flight::bodies
    std::array<double, 3> p{};
    std::array<double, 4> q{1, 0, 0, 0};
};

struct Leg {
    int leg = 0;
    double t_start = 0;
    double t_end = 0;
};

// A vehicle's parameters as meta.json gives them; the physics takes them as they are
// (physics::VehicleParams is this type).
// Each vehicle parameter's range, wherever it is read (meta.json, the physics configuration).
inline constexpr int kMaxRotors = 16;  // the physics holds a planform's rotors in arrays this long
inline constexpr Range kVehicleMassRange{0.01, 100, "kg"};
inline constexpr Range kRotorsRange{1, kMaxRotors};
inline constexpr Range kPropRadiusRange{0.005, 1.0, "m"};
inline constexpr Range kMotorDistanceRange{0.02, 5.0, "m"};

struct VehicleInfo {
    double mass_kg = 0.7;
    int rotors = 4;
    double prop_radius_m = 0.0635;   // 5" propellers
    double motor_distance_m = 0.25;  // diagonal motor-to-motor distance l
};

// Where wrench.csv comes from: a load stand's calibrated wrench, or the force a flying sufferer's
// own model does not explain (mass × IMU acceleration − thrust, as in other labs' logs).
enum class WrenchSource { stand, residual };
const char* to_string(WrenchSource s);

// Where poses.csv comes from: a motion capture (measured from outside, the default), or each
// vehicle's own state estimate (PX4's, when a lab flies without motion capture): meta.json
// "pose_source": "estimate". An estimate follows the vehicle's own sensors and model, so a force
// that moves the vehicle may already be partly in its estimated pose.
enum class PoseSource { motion_capture, estimate };
const char* to_string(PoseSource s);

// meta.json key of a flight exported from a recording (dw-recorder export): the stand's clock
// against the mocap's as the lab's time service measured it live, in seconds, in the sense of the
// explainer's clock effect (a force at mocap time t stamped t + offset).
inline constexpr const char* kMeasuredClockOffsetKey = "clock_offset_measured_s";
// meta.json key beside it: the stand's own pipeline delay as the stand measured it live
// (StandStatus.pipeline_delay_s, median), in seconds — what the stand's wrench stamps lag the
// forces beyond the chips' sample-and-hold; absent where the stand did not measure one.
inline constexpr const char* kStandPipelineDelayKey = "stand_pipeline_delay_s";

// The sufferer's rigid-body name unless a flight or an option names another.
inline constexpr const char* kSufferer = "sufferer";

// meta.json's "reference": another model's prediction of the same wrench, recorded with the flight
// (reference.csv), e.g. the vehicle's own onboard network.
struct ReferenceInfo {
    std::string source;             // the model, in words
    std::vector<std::string> axes;  // the axes it predicts (wrench.csv's names); the others' cells are empty
};

struct Meta {
    std::string sufferer = kSufferer;
    std::vector<std::string> neighbours;
    std::string formation = "free";
    std::map<std::string, VehicleInfo> vehicles;
    std::optional<double> stand_height_m = 1.4;  // absent: the sufferer flies (no load stand)
    WrenchSource wrench_source = WrenchSource::stand;
    bool moments_measured = true;  // false: the moment columns carry no measurement
    PoseSource pose_source = PoseSource::motion_capture;
    std::optional<ReferenceInfo> reference;  // present exactly when reference.csv is
    // What the lab measured live, for a flight exported from a recording (kMeasuredClockOffsetKey,
    // kStandPipelineDelayKey); absent where it was not measured.
    std::optional<double> clock_offset_measured_s;
    std::optional<double> stand_pipeline_delay_s;
    std::string extra_json = "{}";  // unknown keys, kept as they were (a JSON object)
};

struct Flight {
    Meta meta;
    std::vector<std::string> bodies;  // names of the bodies in poses.csv, in first-seen order
    std::vector<WrenchSample> wrench;
    std::vector<PoseSample> poses;
    std::optional<std::vector<Leg>> legs;
    std::vector<WrenchSample> reference;  // reference.csv, on the wrench's clock; NaN where it predicts nothing

    // Index of a body name, adding it if new.
    std::uint16_t body_index(const std::string& name);
    // Index of a body name, or -1.
    int find_body(const std::string& name) const;
};

Flight read_flight(const std::string& dir);
// A meta.json alone (its bodies' names and parameters); throws dw::InputError naming the file and field.
Meta read_meta(const std::string& path);
// Throws dw::InputError "<where>: the flight spans ..." when it holds fewer samples than one per
// kMaxSpanPerSample_s of its span (read_flight checks it; so does every other way a Flight is made
// from a file).
void require_dense(const Flight& f, const std::string& where);
// Writes meta.json, wrench.csv, poses.csv and legs.csv (if any); creates dir. Deterministic bytes.
void write_flight(const Flight& flight, const std::string& dir);

// A flight folder written sample by sample, in the order given (each file's rows must come in time
// order): memory independent of the flight's length. The folder's files appear together at close()
// or not at all (a full disk, a late error): a writer destroyed before close() (a non-finite value,
// a stop) leaves no files, and no folder if it made the folder. Throws dw::RuntimeError (cannot write) or dw::InputError (a value not finite:
// file, row and column).
class FlightWriter {
public:
    explicit FlightWriter(const std::string& dir);
    ~FlightWriter();
    FlightWriter(const FlightWriter&) = delete;
    FlightWriter& operator=(const FlightWriter&) = delete;

    void wrench(const WrenchSample& s);
    void pose(double t, const std::string& body, const std::array<double, 3>& p, const std::array<double, 4>& q);
    // meta.json (and legs.csv, reference.csv), then every file moved into place. Throws
    // dw::InputError when meta.reference and `reference` do not come together.
    void close(const Meta& meta, const std::optional<std::vector<Leg>>& legs = std::nullopt,
               const std::vector<WrenchSample>& reference = {});

private:
    StagedFolder staged_;         // the folder appears whole at close(), or not at all
    std::filesystem::path root_;  // where the files are written until then (staged_.path())
    std::optional<AtomicFile> wrench_, poses_;
    std::string row_;
    std::size_t wrench_rows_ = 0, pose_rows_ = 0;
};

}  // namespace dw::flight
