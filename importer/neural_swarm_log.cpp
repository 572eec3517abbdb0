#include "importer/neural_swarm.hpp"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

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

// A stop is honoured every this many lines, records or resynchronisation offsets (issue 70: a log
// with a 10 MB garbage tail was resynchronised byte by byte, each try a checksum, past SIGINT).
constexpr std::size_t kStopCheckEvery = 4096;

// A CSV log's line is at most this long (the shared logs' are about 750 bytes): a longer one is no
// log's, refused before it is held (a file of one endless line would have filled memory).
constexpr std::size_t kMaxCsvLineBytes = 1 << 16;

struct Limits {
    std::stop_token stop;
    std::size_t max_samples;  // what is left of the trial's kMaxTrialSamples
};

// What a trial may hold is spent (kMaxTrialSamples): `where` is the file and line or byte.
void require_room(const VehicleLog& log, const Limits& limits, const std::string& where) {
    if (log.t_s.size() < limits.max_samples) return;
    throw InputError(log::cat(where, ": more than ", kMaxTrialSamples,
                              " samples in one trial, what an import holds in memory: split the log"));
}

VehicleLog read_csv(const std::string& path, VehicleLog log, const Limits& limits) {
    require_readable_file(path, "log");
    std::ifstream in(path, std::ios::binary);  // line by line: a log is never held whole, nor a line past the cap
    std::vector<char> buffer(kMaxCsvLineBytes + 2);
    std::size_t line_no = 0;
    auto next_line = [&](std::string_view& line) {
        in.getline(buffer.data(), static_cast<std::streamsize>(buffer.size()));
        const auto n = static_cast<std::size_t>(in.gcount());
        if (in.bad()) throw InputError(log::cat(path, ":", line_no + 1, ": cannot read the log"));
        if (in.fail()) {
            if (n == 0 && in.eof()) return false;
            throw InputError(log::cat(path, ":", line_no + 1, ": a line longer than ", kMaxCsvLineBytes,
                                      " bytes: not a Neural-Swarm log"));
        }
        line = std::string_view(buffer.data(), in.eof() ? n : n - 1);  // less the newline getline took
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
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
    for (std::size_t n = 0; next_line(line); ++n) {
        if (n % kStopCheckEvery == 0) throw_if_stopped(limits.stop, "the import");
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
        require_room(log, limits, log::cat(path, ":", line_no));
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

VehicleLog read_binary(const std::string& path, VehicleLog log, const Limits& limits) {
    log.binary = true;
    require_readable_file(path, "log");
    std::error_code ec;
    if (const auto size = fs::file_size(path, ec); !ec && size > kMaxBinaryLogBytes)
        throw InputError(log::cat(path, ": ", size, " bytes, more than a binary log may hold (", kMaxBinaryLogBytes,
                                  "): split the log"));
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
    for (std::size_t n = 0; pos < bytes.size(); ++n) {
        if (n % kStopCheckEvery == 0) throw_if_stopped(limits.stop, "the import");
        const std::size_t k = b[pos], size = 1 + k * record;
        if (pos + size + 4 > bytes.size() || !checksum_ok(b + pos, size)) {
            ++log.damaged_blocks;  // skip to the next offset where a whole block checks out
            std::size_t next = pos + 1;
            while (next < bytes.size() && !(next + 1 + b[next] * record + 4 <= bytes.size() && b[next] > 0 &&
                                            checksum_ok(b + next, 1 + b[next] * record)))
                if (++next % kStopCheckEvery == 0) throw_if_stopped(limits.stop, "the import");
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
            require_room(log, limits, log::cat(path, ": byte ", pos + 1 + r * record));
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

VehicleLog read_neural_swarm_log(const std::string& path, const std::stop_token& stop, std::size_t max_samples) {
    VehicleLog log;
    log.file = path;
    const fs::path p(path);
    log.name = p.stem().string().substr(0, p.stem().string().find('_'));  // cf50_01 -> cf50
    (void)crazyflie_type(log.name);
    log = p.extension() == ".csv" ? read_csv(path, std::move(log), {stop, max_samples})
                                  : read_binary(path, std::move(log), {stop, max_samples});
    if (log.t_s.empty()) throw InputError(log::cat(path, ": no samples"));
    for (std::size_t i = 1; i < log.t_s.size(); ++i) {
        if (!(log.t_s[i] > log.t_s[i - 1]))
            throw InputError(log::cat(path, ": sample ", i + 1, ": time does not increase"));
    }
    return log;
}

}  // namespace dw::importer
