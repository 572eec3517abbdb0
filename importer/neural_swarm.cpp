#include "importer/neural_swarm.hpp"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "core/text.hpp"
#include "flight/flight.hpp"

namespace dw::importer {
namespace {
namespace fs = std::filesystem;

constexpr double kG = 9.81;  // the authors' g for Fa and thrust_des
// The authors' onboard interaction network's prediction of Fa_z (gram-force, z up): the reference.
constexpr const char* kFazField = "ctrlFa.Faz";
constexpr const char* kFazSource =
    "the Neural-Swarm authors' onboard interaction network (ctrlFa.Faz, run on the vehicle in flight)";
constexpr double kThrustLag = 0.84;       // T_lag[i+1] = 0.84 T_lag[i] + 0.16 T[i] (100 Hz)
constexpr double kTareDistance_m = 0.35;  // Fa is tared where every neighbour is farther than this
constexpr double kGap_s = 0.05;           // a longer pause between samples is reported
constexpr double kSteepTilt_rad = 30.0 * M_PI / 180.0;

const std::map<std::string, CrazyflieType>& types() {
    static const std::map<std::string, CrazyflieType> t = {
        {"small",
         {"small",
          0.032,
          0.046,
          0.0225,
          0.07,
          {11.093358483549203, -39.08104165843915, -9.525647087583181, 20.573302305476638, 38.42885066644033}}},
        {"large",
         {"large",
          0.067,
          0.060,
          0.033,
          0.085,
          {44.10386631845999, -122.51151800146272, -36.18484254283743, 53.10772568607133, 107.6819263349139}}},
    };
    return t;
}

// What each logged quantity may be: beyond it a log is damaged, not a flight (issue 43: an az of
// 1e308 was imported). Positions and attitude as a flight folder holds them (flight/flight.hpp).
constexpr Range kTimeUsRange{0, 1e16, "us"};
constexpr Range kAccelRange{-1e3, 1e3, "m/s^2"};  // 100 g
constexpr Range kVelocityRange{-1e3, 1e3, "m/s"};
constexpr Range kPwmRange{0, 1};  // the duty as a fraction (CSV; binary: raw / 65536), as the thrust map takes it
constexpr Range kBatteryRange{0, 100, "V"};
constexpr Range kFazRange{-1e6, 1e6, "gram-force"};

// ---- CSV -----------------------------------------------------------------------------------------

// The CSV columns this importer uses, by header text (the time header says ms; the values are µs).
constexpr std::array<const char*, 18> kCsvColumns = {
    "time[ms]", "x[m]", "y[m]",    "z[m]",    "ax[m/s^2]", "ay[m/s^2]", "az[m/s^2]", "qx",      "qy",
    "qz",       "qw",   "u1[PWM]", "u2[PWM]", "u3[PWM]",   "u4[PWM]",   "Vbat[V]",   "vx[m/s]", "vz[m/s]"};
constexpr std::array<Range, kCsvColumns.size()> kCsvRanges = {kTimeUsRange,
                                                              flight::kPositionRange,
                                                              flight::kPositionRange,
                                                              flight::kPositionRange,
                                                              kAccelRange,
                                                              kAccelRange,
                                                              kAccelRange,
                                                              flight::kQuaternionRange,
                                                              flight::kQuaternionRange,
                                                              flight::kQuaternionRange,
                                                              flight::kQuaternionRange,
                                                              kPwmRange,
                                                              kPwmRange,
                                                              kPwmRange,
                                                              kPwmRange,
                                                              kBatteryRange,
                                                              kVelocityRange,
                                                              kVelocityRange};

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t start = 0;
    for (;;) {
        const auto comma = line.find(',', start);
        out.push_back(line.substr(start, comma == std::string_view::npos ? comma : comma - start));
        if (comma == std::string_view::npos) return out;
        start = comma + 1;
    }
}

VehicleLog read_csv(const std::string& path, VehicleLog log) {
    const std::string text = read_file(path, "log");
    std::size_t pos = 0, line_no = 0;
    auto next_line = [&](std::string_view& line) {
        if (pos >= text.size()) return false;
        auto end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        line = std::string_view(text).substr(pos, end - pos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = end + 1;
        ++line_no;
        return true;
    };
    std::string_view line;
    if (!next_line(line) || line.rfind("# ", 0) != 0)
        throw InputError(log::cat(path, ":1: expected a header line starting with '# '"));
    const auto header = split(line.substr(2));
    std::array<std::size_t, kCsvColumns.size()> at{};
    for (std::size_t c = 0; c < kCsvColumns.size(); ++c) {
        const auto it = std::find(header.begin(), header.end(), kCsvColumns[c]);
        if (it == header.end()) throw InputError(log::cat(path, ":1: column '", kCsvColumns[c], "' is missing"));
        at[c] = static_cast<std::size_t>(it - header.begin());
    }
    double first_us = NAN;
    while (next_line(line)) {
        if (line.empty()) continue;
        const auto f = split(line);
        if (f.size() != header.size())
            throw InputError(log::cat(path, ":", line_no, ": ", f.size(), " fields, expected ", header.size()));
        std::array<double, kCsvColumns.size()> v{};
        for (std::size_t c = 0; c < kCsvColumns.size(); ++c) {
            const auto field = f[at[c]];
            const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), v[c]);
            if (ec != std::errc() || ptr != field.data() + field.size() || !std::isfinite(v[c])) {
                throw InputError(log::cat(path, ":", line_no, ": column ", kCsvColumns[c], ": '",
                                          quote_bytes(field, kQuotedBytes), "' is not a finite number"));
            }
            if (!kCsvRanges[c].contains(v[c]))
                throw InputError(log::cat(path, ":", line_no, ": column ", kCsvColumns[c], ": ",
                                          range_problem(v[c], kCsvRanges[c])));
        }
        if (std::isnan(first_us)) first_us = v[0];
        log.origin.push_back(line_no);
        log.t_s.push_back((v[0] - first_us) * 1e-6);
        log.position_m.push_back({v[1], v[2], v[3]});
        log.accel_mps2.push_back({v[4], v[5], v[6]});
        log.quat_xyzw.push_back({v[7], v[8], v[9], v[10]});
        log.pwm.push_back({v[11], v[12], v[13], v[14]});
        log.vbat_v.push_back(v[15]);
    }
    return log;
}

// ---- binary --------------------------------------------------------------------------------------

struct Field {
    std::string name;
    char type;
    std::size_t offset;
};

std::size_t type_size(char t) { return t == 'h' || t == 'H' ? 2 : 4; }

double read_value(const std::uint8_t* p, char type) {
    switch (type) {
        case 'I': {
            std::uint32_t v;
            std::memcpy(&v, p, 4);
            return v;
        }
        case 'h': {
            std::int16_t v;
            std::memcpy(&v, p, 2);
            return v;
        }
        case 'H': {
            std::uint16_t v;
            std::memcpy(&v, p, 2);
            return v;
        }
        default: {
            float v;
            std::memcpy(&v, p, 4);
            return v;
        }
    }
}

// The Crazyflie's compressed quaternion: the largest component's index in the top 2 bits, the
// other three as sign + 9-bit magnitude (511 = 1/√2), the highest index in the lowest bits.
std::array<double, 4> decompress_quaternion(std::uint32_t packed) {
    constexpr std::uint32_t kMask = (1u << 9) - 1;
    const unsigned largest = packed >> 30;
    std::array<double, 4> q{};
    double sum = 0;
    for (int i = 3; i >= 0; --i) {
        if (static_cast<unsigned>(i) == largest) continue;
        const double mag = M_SQRT1_2 * static_cast<double>(packed & kMask) / kMask;
        q[static_cast<std::size_t>(i)] = ((packed >> 9) & 1u) ? -mag : mag;
        packed >>= 10;
        sum += mag * mag;
    }
    q[largest] = std::sqrt(std::max(0.0, 1.0 - sum));
    return q;
}

bool checksum_ok(const std::uint8_t* data, std::size_t n) {
    std::uint32_t stored = 0;
    std::memcpy(&stored, data + n, 4);
    const auto crc = static_cast<std::uint32_t>(::crc32(0L, data, static_cast<uInt>(n)));
    return stored == static_cast<std::uint32_t>(~crc);
}

std::vector<Field> binary_header(const std::string& path, const std::string& bytes, std::size_t& pos) {
    const auto* b = reinterpret_cast<const std::uint8_t*>(bytes.data());
    if (bytes.empty()) throw InputError(log::cat(path, ": empty file"));
    const std::size_t n = b[0];
    std::vector<Field> fields;
    std::size_t offset = 0;
    pos = 1;
    while (fields.size() < n) {
        const auto comma = bytes.find(',', pos);
        if (comma == std::string::npos || comma - pos < 4)
            throw InputError(log::cat(path, ": byte ", pos, ": the header ends early"));
        const std::string entry = bytes.substr(pos, comma - pos);  // name(T)
        const char type = entry[entry.size() - 2];
        if (entry[entry.size() - 3] != '(' || entry.back() != ')' ||
            std::string("IhHf").find(type) == std::string::npos) {
            throw InputError(log::cat(path, ": byte ", pos, ": '", quote_bytes(entry, kQuotedBytes),
                                      "' is not name(T) with T one of I h H f"));
        }
        fields.push_back({entry.substr(0, entry.size() - 3), type, offset});
        offset += type_size(type);
        pos = comma + 1;
    }
    if (bytes.size() < pos + 4 || !checksum_ok(b, pos))
        throw InputError(log::cat(path, ": byte ", pos, ": header checksum mismatch"));
    pos += 4;
    return fields;
}

VehicleLog read_binary(const std::string& path, VehicleLog log) {
    log.binary = true;
    const std::string bytes = read_file(path, "log");
    std::size_t pos = 0;
    const auto fields = binary_header(path, bytes, pos);
    std::size_t record = 0;
    for (const auto& f : fields) record += type_size(f.type);
    auto field = [&](const char* name) {
        const auto it = std::find_if(fields.begin(), fields.end(), [&](const Field& f) { return f.name == name; });
        if (it == fields.end()) throw InputError(log::cat(path, ": variable '", name, "' is not logged"));
        return *it;
    };
    const Field tick = field("tick"), x = field("stateEstimateZ.x"), y = field("stateEstimateZ.y"),
                z = field("stateEstimateZ.z"), ax = field("stateEstimateZ.ax"), ay = field("stateEstimateZ.ay"),
                az = field("stateEstimateZ.az"), quat = field("stateEstimateZ.quat"), vbat = field("pm.vbatMV");
    const std::array<Field, 4> pwm = {field("pwm.m1_pwm"), field("pwm.m2_pwm"), field("pwm.m3_pwm"),
                                      field("pwm.m4_pwm")};
    const auto faz = std::find_if(fields.begin(), fields.end(), [](const Field& f) { return f.name == kFazField; });
    const auto* b = reinterpret_cast<const std::uint8_t*>(bytes.data());
    double first_us = NAN;
    while (pos < bytes.size()) {
        const std::size_t k = b[pos], size = 1 + k * record;
        if (pos + size + 4 > bytes.size() || !checksum_ok(b + pos, size)) {
            ++log.damaged_blocks;  // skip to the next offset where a whole block checks out
            std::size_t next = pos + 1;
            while (next < bytes.size() && !(next + 1 + b[next] * record + 4 <= bytes.size() && b[next] > 0 &&
                                            checksum_ok(b + next, 1 + b[next] * record)))
                ++next;
            pos = next;
            continue;
        }
        for (std::size_t r = 0; r < k; ++r) {
            const std::uint8_t* rec = b + pos + 1 + r * record;
            auto v = [&](const Field& f, const Range& range, double scale = 1) {
                const double value = read_value(rec + f.offset, f.type) / scale;
                if (!range.contains(value))
                    throw InputError(log::cat(path, ": byte ", pos + 1 + r * record + f.offset, ": variable '",
                                              quote_bytes(f.name, kQuotedBytes), "': ", range_problem(value, range)));
                return value;
            };
            if (std::isnan(first_us)) first_us = v(tick, kTimeUsRange);
            log.origin.push_back(pos + 1 + r * record);
            log.t_s.push_back((v(tick, kTimeUsRange) - first_us) * 1e-6);
            log.position_m.push_back({v(x, flight::kPositionRange, 1000), v(y, flight::kPositionRange, 1000),
                                      v(z, flight::kPositionRange, 1000)});
            log.accel_mps2.push_back({v(ax, kAccelRange, 1000), v(ay, kAccelRange, 1000), v(az, kAccelRange, 1000)});
            std::uint32_t packed = 0;
            std::memcpy(&packed, rec + quat.offset, 4);
            log.quat_xyzw.push_back(decompress_quaternion(packed));
            log.pwm.push_back({v(pwm[0], kPwmRange, 65536), v(pwm[1], kPwmRange, 65536), v(pwm[2], kPwmRange, 65536),
                               v(pwm[3], kPwmRange, 65536)});
            log.vbat_v.push_back(v(vbat, kBatteryRange, 1000));
            if (faz != fields.end()) log.faz_g.push_back(v(*faz, kFazRange));
        }
        pos += size + 4;
    }
    return log;
}

}  // namespace

std::string VehicleLog::where(std::size_t sample) const {
    if (sample >= origin.size()) return log::cat(file, ": sample ", sample + 1);
    return binary ? log::cat(file, ": byte ", origin[sample]) : log::cat(file, ":", origin[sample]);
}

const CrazyflieType& crazyflie_type(const std::string& vehicle) {
    // cf50..cf52: Crazyflie 2.1; cf100..cf102: on a parrot frame (the collection's README).
    int id = -1;
    if (vehicle.rfind("cf", 0) == 0) std::from_chars(vehicle.data() + 2, vehicle.data() + vehicle.size(), id);
    if (id >= 50 && id <= 52) return types().at("small");
    if (id >= 100 && id <= 102) return types().at("large");
    throw InputError(
        log::cat("vehicle '", vehicle, "': not one the Neural-Swarm collection describes (cf50-cf52, cf100-cf102)"));
}

VehicleLog read_neural_swarm_log(const std::string& path) {
    VehicleLog log;
    log.file = path;
    const fs::path p(path);
    log.name = p.stem().string().substr(0, p.stem().string().find('_'));  // cf50_01 -> cf50
    (void)crazyflie_type(log.name);
    log = p.extension() == ".csv" ? read_csv(path, std::move(log)) : read_binary(path, std::move(log));
    if (log.t_s.empty()) throw InputError(log::cat(path, ": no samples"));
    for (std::size_t i = 1; i < log.t_s.size(); ++i) {
        if (!(log.t_s[i] > log.t_s[i - 1]))
            throw InputError(log::cat(path, ": sample ", i + 1, ": time does not increase"));
    }
    return log;
}

namespace {

double thrust_n(const CrazyflieType& type, const std::array<double, 4>& pwm, double vbat_v) {
    const auto& c = type.thrust_g;
    const double v = vbat_v / 4.2;
    double grams = 0;
    for (double p : pwm) grams += c[0] + c[1] * p + c[2] * v + c[3] * p * p + c[4] * v * p;
    return grams * kG / 1000.0;
}

// The body z axis in the world frame (third column of R) from a scalar-last quaternion.
std::array<double, 3> body_z(const std::array<double, 4>& q) {
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    return {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)};
}

std::array<double, 3> position_at(const VehicleLog& log, double t) {
    const auto it = std::lower_bound(log.t_s.begin(), log.t_s.end(), t);
    if (it == log.t_s.begin()) return log.position_m.front();
    if (it == log.t_s.end()) return log.position_m.back();
    const auto i = static_cast<std::size_t>(it - log.t_s.begin());
    const double a = (t - log.t_s[i - 1]) / (log.t_s[i] - log.t_s[i - 1]);
    std::array<double, 3> p{};
    for (std::size_t k = 0; k < 3; ++k)
        p[k] = log.position_m[i - 1][k] + a * (log.position_m[i][k] - log.position_m[i - 1][k]);
    return p;
}

double median(std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

void warn_about(const VehicleLog& log, const ImportOptions& o) {
    if (!o.warn) return;
    const auto& type = crazyflie_type(log.name);
    double worst_gap = 0, lowest = INFINITY, steepest = 0;
    std::size_t gaps = 0, touches = 0;
    for (std::size_t i = 0; i < log.t_s.size(); ++i) {
        if (i > 0 && log.t_s[i] - log.t_s[i - 1] > kGap_s)
            ++gaps, worst_gap = std::max(worst_gap, log.t_s[i] - log.t_s[i - 1]);
        if (log.position_m[i][2] < type.ground_z_m) ++touches;
        lowest = std::min(lowest, log.position_m[i][2]);
        steepest = std::max(steepest, std::acos(std::clamp(body_z(log.quat_xyzw[i])[2], -1.0, 1.0)));
    }
    if (gaps) o.warn(log::cat(log.file, ": ", gaps, " gap(s) in the log, the longest ", worst_gap, " s"));
    if (touches)
        o.warn(log::cat(log.file, ": ", touches, " sample(s) below z = ", type.ground_z_m, " m: touching the ground"));
    if (steepest > kSteepTilt_rad) o.warn(log::cat(log.file, ": tilts up to ", steepest * 180 / M_PI, " degrees"));
    if (log.damaged_blocks)
        o.warn(log::cat(log.file, ": ", log.damaged_blocks, " damaged block(s) skipped (checksum)"));
}

// What a flight may hold (flight::kForceRange), checked where a sample's force is derived: each
// input is in its own range, but together (full PWM at 100 V) they can make an absurd thrust.
double require_force(const VehicleLog& s, std::size_t i, const char* what, double v) {
    if (!flight::kForceRange.contains(v))
        throw InputError(log::cat(s.where(i), ": ", what, ": ", range_problem(v, flight::kForceRange)));
    return v;
}

// Fa = m a_imu − T_lag R e_z (world, z up), tared where no neighbour is near. Returns the tare.
std::array<double, 3> residuals(const VehicleLog& s, const std::vector<VehicleLog>& others, const ImportOptions& o,
                                std::vector<std::array<double, 3>>& fa) {
    const auto& type = crazyflie_type(s.name);
    double lag = thrust_n(type, s.pwm.front(), s.vbat_v.front());
    std::array<std::vector<double>, 3> far;
    for (std::size_t i = 0; i < s.t_s.size(); ++i) {
        const auto ez = body_z(s.quat_xyzw[i]);
        std::array<double, 3> f{};
        for (std::size_t k = 0; k < 3; ++k) f[k] = type.mass_kg * s.accel_mps2[i][k] - lag * ez[k];
        for (const double v : f) require_force(s, i, "the residual force", v);
        const double thrust = thrust_n(type, s.pwm[i], s.vbat_v[i]);
        lag = kThrustLag * lag +
              (1 - kThrustLag) * require_force(s, i, "the thrust of its PWM and battery voltage", thrust);
        fa.push_back(f);
        bool alone = true;
        for (const auto& n : others) {
            const auto p = position_at(n, s.t_s[i]);
            alone = alone && std::hypot(p[0] - s.position_m[i][0], p[1] - s.position_m[i][1]) > kTareDistance_m;
        }
        if (alone)
            for (std::size_t k = 0; k < 3; ++k) far[k].push_back(f[k]);
    }
    std::array<double, 3> tare{};
    if (far[0].size() < 20) {
        if (o.warn)
            o.warn(log::cat(s.file, ": fewer than 20 samples with every neighbour > ", kTareDistance_m,
                            " m away: Fa not tared"));
        return tare;
    }
    for (std::size_t k = 0; k < 3; ++k) tare[k] = median(far[k]);
    for (auto& f : fa)
        for (std::size_t k = 0; k < 3; ++k) f[k] -= tare[k];
    return tare;
}

// World z-up (x, y, z) -> NED (n, e, d): a half turn about x. Quaternions: (w, x, -y, -z).
std::array<double, 3> to_ned(const std::array<double, 3>& v) { return {v[0], -v[1], -v[2]}; }

// A log that is not two folders deep (at /, or in a folder at /).
constexpr const char* kUnknownCollection = "(unknown collection)";

nlohmann::json source_of(const std::vector<VehicleLog>& logs) {
    std::vector<std::string> files;
    nlohmann::json names = nlohmann::json::array();
    for (const auto& l : logs) {
        files.push_back(l.file);
        // <experiment>/<log>: a trial's logs are named alike across experiments (swap_ss/cf50_02 and
        // randomwalk_ss/cf50_02 are two trials).
        const fs::path p = fs::absolute(fs::path(l.file)).lexically_normal();
        names.push_back((p.parent_path().filename() / p.filename()).string());
    }
    return {{"collection", "aerorobotics/neural-swarm " + collection_of(files)}, {"logs", names}};
}

// The collection's readme: "do not use the Fa of cf100" (a Crazyflie 2.0, much worse IMU).
constexpr std::array<const char*, 1> kUnusableResidual{"cf100"};
constexpr const char* kUnusableResidualWhy = "a Crazyflie 2.0 with a much worse IMU, the collection's readme";
bool residual_usable(const std::string& vehicle) {
    return std::find(kUnusableResidual.begin(), kUnusableResidual.end(), vehicle) == kUnusableResidual.end();
}

// The onboard network's Fa_z as reference.csv's f_d (NED, newtons), where it ran: in older
// collections it is 0 throughout (the network was off), which is no prediction.
void add_reference(flight::Flight& f, const VehicleLog& s, const ImportOptions& o) {
    if (s.faz_g.empty()) return;
    if (std::all_of(s.faz_g.begin(), s.faz_g.end(), [](double g) { return g == 0.0; })) {
        if (o.warn)
            o.warn(log::cat(s.file, ": ", kFazField, " is 0 throughout (the onboard network was off): no reference"));
        return;
    }
    f.meta.reference = flight::ReferenceInfo{kFazSource, {"f_d"}};
    for (std::size_t i = 0; i < s.t_s.size(); ++i)
        f.reference.push_back({s.t_s[i], {NAN, NAN, -s.faz_g[i] * kG / 1000.0, NAN, NAN, NAN}});
}

flight::Flight to_flight(std::vector<VehicleLog> logs, const ImportOptions& o) {
    std::map<std::string, int> seen;
    for (const auto& l : logs) {
        if (seen[l.name]++) throw InputError(log::cat(l.file, ": a second log of ", l.name, " in one trial"));
        warn_about(l, o);
    }
    auto lowest = [](const VehicleLog& l) {
        std::vector<double> z;
        for (const auto& p : l.position_m) z.push_back(p[2]);
        return median(z);
    };
    std::string sufferer = o.sufferer;
    if (sufferer.empty()) {  // the lowest vehicle whose residual the authors trust
        const VehicleLog* best = nullptr;
        for (const auto& l : logs)
            if (residual_usable(l.name) && (!best || lowest(l) < lowest(*best))) best = &l;
        sufferer = (best ? *best : logs.front()).name;
    } else if (!residual_usable(sufferer) && o.warn) {
        o.warn(log::cat(sufferer, ": the authors say not to use this vehicle's residual (", kUnusableResidualWhy, ")"));
    }
    const auto it = std::find_if(logs.begin(), logs.end(), [&](const VehicleLog& l) { return l.name == sufferer; });
    if (it == logs.end()) throw InputError(log::cat("--sufferer: no log of '", sufferer, "' among the inputs"));
    std::vector<VehicleLog> others;
    for (const auto& l : logs)
        if (l.name != sufferer) others.push_back(l);
    if (others.empty())
        throw InputError("a trial needs the logs of at least two vehicles (a sufferer and a neighbour)");

    flight::Flight f;
    f.meta.sufferer = sufferer;
    f.meta.formation = "free";
    f.meta.stand_height_m.reset();
    f.meta.wrench_source = flight::WrenchSource::residual;
    f.meta.moments_measured = false;
    std::vector<std::array<double, 3>> fa;
    const auto tare = residuals(*it, others, o, fa);
    for (std::size_t i = 0; i < it->t_s.size(); ++i) {
        const auto ned = to_ned(fa[i]);
        f.wrench.push_back({it->t_s[i], {ned[0], ned[1], ned[2], 0, 0, 0}});
    }
    add_reference(f, *it, o);
    struct Pose {
        double t;
        std::uint16_t body;
        std::array<double, 3> p;
        std::array<double, 4> q;
    };
    std::vector<Pose> poses;
    for (const auto& l : logs) {
        const auto& type = crazyflie_type(l.name);
        const std::uint16_t body = f.body_index(l.name);
        if (l.name != sufferer) f.meta.neighbours.push_back(l.name);
        f.meta.vehicles[l.name] = {type.mass_kg, 4, type.prop_radius_m,
                                   2 * type.arm_m};  // motor_distance_m: diagonal, motor to motor
        for (std::size_t i = 0; i < l.t_s.size(); ++i) {
            throw_if_stopped(o.stop, "the import");
            const auto& q = l.quat_xyzw[i];
            const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            poses.push_back({l.t_s[i], body, to_ned(l.position_m[i]), {q[3] / n, q[0] / n, -q[1] / n, -q[2] / n}});
        }
    }
    std::stable_sort(poses.begin(), poses.end(), [](const Pose& a, const Pose& b) { return a.t < b.t; });
    for (const auto& p : poses) f.poses.push_back({p.t, p.body, p.p, p.q});
    f.meta.extra_json =
        nlohmann::json{
            {"source", source_of(logs)},
            {"residual",
             {{"definition", "Fa = m a_imu - T_lag R e_z (the authors'), NED"},
              {"thrust", "per motor c00 + c10 p + c01 v + c20 p^2 + c11 v p gram-force, p = PWM, v = Vbat/4.2"},
              {"thrust_lag", kThrustLag},
              {"tare_n", {to_ned(tare)[0], to_ned(tare)[1], to_ned(tare)[2]}},
              {"tare_rule", "median Fa where every neighbour is > 0.35 m away horizontally"}}},
            {"clocks",
             "each log from its own first sample; the logs of a trial taken as simultaneous (the authors' alignment)"}}
            .dump();
    return f;
}

class NeuralSwarm final : public Importer {
public:
    std::string_view name() const override { return "neural-swarm"; }
    std::string_view description() const override {
        return "Crazyflie logs of aerorobotics/neural-swarm (CSV or binary micro-SD logs), one file per vehicle of a "
               "trial";
    }
    flight::Flight import(const std::vector<std::string>& files, const ImportOptions& o) const override {
        std::vector<VehicleLog> logs;
        for (const auto& file : files) {
            throw_if_stopped(o.stop, "the import");
            logs.push_back(read_neural_swarm_log(file));
        }
        return to_flight(std::move(logs), o);
    }
};

}  // namespace

std::string collection_of(const std::vector<std::string>& log_files) {
    std::string found, first;
    for (const auto& file : log_files) {
        std::string c = fs::absolute(fs::path(file)).lexically_normal().parent_path().parent_path().filename().string();
        if (c.empty()) c = kUnknownCollection;
        if (first.empty()) {
            found = c;
            first = file;
        } else if (c != found) {
            throw InputError(log::cat("the logs of one trial come from two collections: ", first, " (", found, ") and ",
                                      file, " (", c, ")"));
        }
    }
    return found;
}

std::vector<CollectionTrial> collection_trials(const std::string& dir) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw InputError(log::cat(dir, ": not a folder of Neural-Swarm experiments"));
    std::map<std::string, std::map<std::string, fs::path>> trials;  // name -> vehicle -> log
    for (const auto& experiment : fs::directory_iterator(dir, ec)) {
        if (!experiment.is_directory(ec)) continue;
        for (const auto& file : fs::directory_iterator(experiment.path(), ec)) {
            const fs::path p = file.path();
            const std::string stem = p.stem().string();
            const auto cut = stem.find('_');
            if (!file.is_regular_file(ec) || cut == std::string::npos || (p.has_extension() && p.extension() != ".csv"))
                continue;
            auto& log = trials[experiment.path().filename().string() + stem.substr(cut)][stem.substr(0, cut)];
            if (log.empty() || !p.has_extension()) log = p;  // the binary log wins over the CSV made from it
        }
    }
    if (ec) throw InputError(log::cat(dir, ": ", ec.message()));
    std::vector<CollectionTrial> out;
    for (const auto& [name, logs] : trials) {
        out.push_back({name, {}});
        for (const auto& [vehicle, path] : logs) out.back().logs.push_back(path.string());
    }
    if (out.empty()) throw InputError(log::cat(dir, ": no Neural-Swarm trial (<experiment>/<vehicle>_<trial> logs)"));
    return out;
}

const Importer& neural_swarm_importer() {
    static const NeuralSwarm importer;
    return importer;
}

}  // namespace dw::importer
