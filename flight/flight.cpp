#include "flight/flight.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <ranges>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include "core/errors.hpp"
#include "core/clock.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/text.hpp"
#include "flight/csv.hpp"
#include "flight/reference.hpp"

namespace dw::flight {
namespace fs = std::filesystem;
using csv::CsvReader;
using csv::Row;
using nlohmann::json;

namespace {
constexpr int kMaxJsonDepth = 64;  // meta.json nests 3 deep; 100 000 crashed a JSON library's destructor
constexpr Range kLegNumberRange{0, 1e6};
// The meta.json keys this library reads; every other key is kept as it was (extra_json).
constexpr std::array<const char*, 12> kMetaKeys = {"format",
                                                   "sufferer",
                                                   "neighbours",
                                                   "formation",
                                                   "vehicles",
                                                   "stand",
                                                   "moments_measured",
                                                   "reference",
                                                   "pose_source",
                                                   "wrench_source",
                                                   kMeasuredClockOffsetKey,
                                                   kStandPipelineDelayKey};
constexpr std::array<std::pair<PoseSource, const char*>, 2> kPoseSourceNames{
    {{PoseSource::motion_capture, "motion_capture"}, {PoseSource::estimate, "estimate"}}};
}  // namespace

const char* to_string(WrenchSource s) { return s == WrenchSource::stand ? "stand" : "residual"; }
const char* to_string(PoseSource s) {
    for (const auto& [source, name] : kPoseSourceNames)
        if (source == s) return name;
    return "";
}

std::string axis_list() { return log::alternatives(kAxes); }

std::vector<std::string> wrench_columns() {
    std::vector<std::string> c{"t"};
    c.insert(c.end(), kAxes.begin(), kAxes.end());
    return c;
}

const Range& axis_range(std::size_t axis) { return axis < 3 ? kForceRange : kMomentRange; }

std::string body_name_problem(std::string_view name) {
    if (name.empty()) return "empty";
    if (name.size() > kMaxNameBytes) return log::cat("longer than ", kMaxNameBytes, " bytes");
    if (!valid_utf8(name)) return log::cat("'", quote_bytes(name, kQuotedBytes), "' is not UTF-8");
    for (const char c : name) {
        if (c == ',' || c == '"' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            return log::cat("'", quote_bytes(name, kQuotedBytes),
                            "' holds a comma, a double quote or a control byte (it would not read back)");
    }
    return "";
}

std::uint16_t Flight::body_index(const std::string& name) {
    const int i = find_body(name);
    if (i >= 0) return static_cast<std::uint16_t>(i);
    if (bodies.size() >= kMaxBodies) throw InputError(log::cat("a flight holds at most ", kMaxBodies, " bodies"));
    bodies.push_back(name);
    return static_cast<std::uint16_t>(bodies.size() - 1);
}

int Flight::find_body(const std::string& name) const {
    auto it = std::find(bodies.begin(), bodies.end(), name);
    return it == bodies.end() ? -1 : static_cast<int>(it - bodies.begin());
}

namespace {

std::string slurp(const fs::path& path) { return read_file(path.string(), "flight file"); }

std::string json_location(const std::string& text, std::size_t byte) {
    std::size_t line = 1, col = 1;
    // nlohmann's byte is the 1-based index of the character where parsing failed.
    for (std::size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    return log::cat(line, ":", col);
}

// meta.json's fields, each error naming the file and the field.
class MetaReader {
public:
    explicit MetaReader(const fs::path& path) : file_(path.string()) {
        const std::string text = slurp(path);
        require_nesting_at_most(text, kMaxJsonDepth, file_);
        std::string duplicate;
        try {
            j_ = json::parse(text, duplicate_key_finder(duplicate));
        } catch (const json::parse_error& e) {
            throw InputError(log::cat(file_, ":", json_location(text, e.byte), ": not valid JSON"));
        } catch (const json::exception& e) {  // a number past a double's range (1e400), and the like
            throw InputError(log::cat(file_, ": not valid JSON: ", quote_bytes(e.what(), kQuotedBytes)));
        }
        if (!duplicate.empty()) fail(duplicate, "given twice (which one counts?)");
        if (!j_.is_object()) fail("(top)", "expected a JSON object");
        if (!j_.contains("format") || j_["format"] != kFormat) {
            fail("format",
                 log::cat("expected \"", kFormat, "\", got ",
                          j_.contains("format") ? quote_bytes(j_["format"].dump(), kQuotedBytes) : "nothing"));
        }
    }
    Meta read() const {
        Meta m;
        m.sufferer = string_of("sufferer");
        require_body_name("sufferer", m.sufferer);
        m.formation = string_of("formation");
        if (std::find_if(kFormations.begin(), kFormations.end(), [&](const char* f) { return m.formation == f; }) ==
            kFormations.end()) {
            fail("formation",
                 log::cat("'", quote_bytes(m.formation, kQuotedBytes), "' is not one of ", log::join(kFormations)));
        }
        read_neighbours(m);
        read_vehicles(m);
        read_stand(m);
        read_wrench_source(m);
        read_pose_source(m);
        read_reference(m);
        read_measured_timing(m);
        json extra = json::object();
        for (const auto& [k, v] : j_.items())
            if (std::find(kMetaKeys.begin(), kMetaKeys.end(), k) == kMetaKeys.end()) extra[k] = v;
        m.extra_json = extra.dump();
        return m;
    }

private:
    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw InputError(log::cat(file_, ": field '", quote_bytes(key, kQuotedBytes), "': ", what));
    }
    // A parser callback that notes the first key given twice in one object (the JSON library keeps
    // the last silently).
    static json::parser_callback_t duplicate_key_finder(std::string& duplicate) {
        return [&duplicate, keys = std::vector<std::set<std::string>>{}](int, json::parse_event_t event,
                                                                         json& parsed) mutable {
            if (event == json::parse_event_t::object_start) keys.emplace_back();
            if (event == json::parse_event_t::object_end) keys.pop_back();
            if (event == json::parse_event_t::key && !keys.back().insert(parsed.get<std::string>()).second &&
                duplicate.empty())
                duplicate = parsed.get<std::string>();
            return true;
        };
    }
    std::string string_of(const std::string& key) const {
        if (!j_.contains(key) || !j_[key].is_string()) fail(key, "missing or not a string");
        return j_[key].get<std::string>();
    }
    void require_body_name(const std::string& key, const std::string& name) const {
        if (const auto problem = body_name_problem(name); !problem.empty()) fail(key, "a body name: " + problem);
    }
    void read_neighbours(Meta& m) const {
        if (!j_.contains("neighbours") || !j_["neighbours"].is_array()) fail("neighbours", "missing or not a list");
        for (const auto& n : j_["neighbours"]) {
            if (!n.is_string()) fail("neighbours", "every entry must be a string");
            const std::string name = n.get<std::string>();
            require_body_name("neighbours", name);
            if (name == m.sufferer) fail("neighbours", log::cat("'", name, "' is the sufferer"));
            if (std::find(m.neighbours.begin(), m.neighbours.end(), name) != m.neighbours.end()) {
                fail("neighbours", log::cat("'", name, "' is listed twice (its force would count twice)"));
            }
            m.neighbours.push_back(name);
        }
    }
    // The lab's measured clock offset and the stand's pipeline delay must be times a lab could
    // measure (a 1e300 s offset was printed in full by the explainer).
    void read_measured_timing(Meta& m) const {
        for (const auto& [key, range, to] :
             {std::tuple{kMeasuredClockOffsetKey, kClockOffsetRange, &Meta::clock_offset_measured_s},
              {kStandPipelineDelayKey, kPipelineDelayRange, &Meta::stand_pipeline_delay_s}}) {
            if (!j_.contains(key)) continue;
            if (!j_[key].is_number()) fail(key, "not a number");
            if (!range.contains(j_[key].get<double>())) fail(key, range_problem(j_[key].get<double>(), range));
            m.*to = j_[key].get<double>();
        }
    }
    void read_vehicles(Meta& m) const {
        if (!j_.contains("vehicles")) return;
        if (!j_["vehicles"].is_object()) fail("vehicles", "not an object");
        for (const auto& [name, v] : j_["vehicles"].items()) {
            require_body_name("vehicles", name);
            const std::string key = "vehicles." + name;
            if (!v.is_object()) fail(key, "not an object");
            VehicleInfo info;
            auto num = [&](const char* field, double& out, const Range& range) {
                if (!v.contains(field)) return;
                if (!v[field].is_number()) fail(key + "." + field, "not a number");
                out = v[field].get<double>();
                if (!range.contains(out)) fail(key + "." + field, range_problem(out, range));
            };
            num("mass_kg", info.mass_kg, kVehicleMassRange);
            num("prop_radius_m", info.prop_radius_m, kPropRadiusRange);
            num("motor_distance_m", info.motor_distance_m, kMotorDistanceRange);
            if (v.contains("rotors")) {  // read wide: 2^32 + 1 must not wrap to 1
                const auto& r = v["rotors"];
                if (!r.is_number_integer()) fail(key + ".rotors", "not an integer");
                const double n = r.is_number_unsigned() ? static_cast<double>(r.get<std::uint64_t>())
                                                        : static_cast<double>(r.get<std::int64_t>());
                if (!kRotorsRange.contains(n)) fail(key + ".rotors", range_problem(n, kRotorsRange));
                info.rotors = static_cast<int>(n);
            }
            m.vehicles[name] = info;
        }
    }
    void read_stand(Meta& m) const {
        if (!j_.contains("stand")) {
            m.stand_height_m.reset();
            return;
        }
        const auto& s = j_["stand"];
        if (!s.is_object()) fail("stand", "not an object");
        if (s.contains("height_m")) {
            if (!s["height_m"].is_number()) fail("stand.height_m", "not a number");
            const double h = s["height_m"].get<double>();
            if (!kStandHeightRange.contains(h)) fail("stand.height_m", range_problem(h, kStandHeightRange));
            m.stand_height_m = h;
        }
    }
    void read_wrench_source(Meta& m) const {
        if (j_.contains("wrench_source")) {
            const auto& w = j_["wrench_source"];
            if (w == to_string(WrenchSource::stand)) m.wrench_source = WrenchSource::stand;
            else if (w == to_string(WrenchSource::residual)) m.wrench_source = WrenchSource::residual;
            else
                fail("wrench_source",
                     log::cat(quote_bytes(w.dump(), kQuotedBytes), " is not \"stand\" or \"residual\""));
        }
        if (j_.contains("moments_measured")) {
            if (!j_["moments_measured"].is_boolean()) fail("moments_measured", "not true or false");
            m.moments_measured = j_["moments_measured"].get<bool>();
        }
    }
    void read_pose_source(Meta& m) const {
        if (!j_.contains("pose_source")) return;
        const auto& p = j_["pose_source"];
        for (const auto& [source, name] : kPoseSourceNames)
            if (p == name) return void(m.pose_source = source);
        const auto names = std::views::transform(kPoseSourceNames, [](const auto& n) { return n.second; });
        fail("pose_source", log::cat(quote_bytes(p.dump(), kQuotedBytes), " is not ", log::alternatives(names)));
    }

    void read_reference(Meta& m) const {
        if (!j_.contains("reference")) return;
        const auto& r = j_["reference"];
        if (!r.is_object() || !r.contains("source") || !r["source"].is_string())
            fail("reference", "not an object with a \"source\" text");
        if (!r.contains("axes") || !r["axes"].is_array() || r["axes"].empty())
            fail("reference.axes", "missing or not a list of axis names");
        ReferenceInfo info{r["source"].get<std::string>(), {}};
        for (const auto& a : r["axes"]) {
            const std::string name = a.is_string() ? a.get<std::string>() : a.dump();
            if (std::find(kAxes.begin(), kAxes.end(), name) == kAxes.end())
                fail("reference.axes", log::cat("'", quote_bytes(name, kQuotedBytes), "' is not one of ", axis_list()));
            if (std::find(info.axes.begin(), info.axes.end(), name) != info.axes.end())
                fail("reference.axes", log::cat("'", name, "' is listed twice"));
            info.axes.push_back(name);
        }
        m.reference = info;
    }

    std::string file_;
    json j_;
};

}  // namespace

Meta read_meta(const std::string& path) { return MetaReader(path).read(); }

void require_dense(const Flight& f, const std::string& where) {
    if (f.wrench.empty() || f.poses.empty()) return;
    double lo = std::min(f.wrench.front().t, f.poses.front().t);
    double hi = std::max(f.wrench.back().t, f.poses.back().t);
    for (const auto& l : f.legs.value_or(std::vector<Leg>{})) lo = std::min(lo, l.t_start), hi = std::max(hi, l.t_end);
    const std::size_t samples = f.wrench.size() + f.poses.size();
    if (hi - lo <= kMaxSpanPerSample_s * static_cast<double>(samples)) return;
    throw InputError(log::cat(where, ": the flight spans ", hi - lo, " s (wrench.csv t = ", f.wrench.front().t, "..",
                              f.wrench.back().t, ", poses.csv t = ", f.poses.front().t, "..", f.poses.back().t,
                              ") with ", samples, " samples, fewer than one per ", kMaxSpanPerSample_s,
                              " s: a stray stamp or a gap"));
}

namespace {

void read_wrench(const fs::path& root, Flight& f) {
    CsvReader csv(slurp(root / "wrench.csv"), (root / "wrench.csv").string());
    csv.expect_header(wrench_columns());
    std::vector<std::string_view> row;
    while (csv.next(row)) {
        WrenchSample s;
        s.t = csv.number(row[0], 0, kStampRange);
        for (std::size_t i = 0; i < 6; ++i) s.w[i] = csv.number(row[i + 1], i + 1, axis_range(i));
        if (!f.wrench.empty() && s.t < f.wrench.back().t) {
            csv.fail(csv.line(),
                     log::cat("t = ", row[0], " is earlier than the row before (rows must be sorted by t)"));
        }
        f.wrench.push_back(s);
    }
    if (f.wrench.empty()) csv.fail(1, "no samples");
}

void read_poses(const fs::path& root, Flight& f) {
    CsvReader csv(slurp(root / "poses.csv"), (root / "poses.csv").string());
    csv.expect_header({"t", "body", "n", "e", "d", "qw", "qx", "qy", "qz"});
    std::vector<std::string_view> row;
    while (csv.next(row)) {
        PoseSample s;
        s.t = csv.number(row[0], 0, kStampRange);
        const std::string name(row[1]);
        int body = f.find_body(name);  // one look-up per row: a new name is checked, then added
        if (body < 0) {
            if (const auto problem = body_name_problem(name); !problem.empty())
                csv.fail(csv.line(), "column body: " + problem);
            if (f.bodies.size() >= kMaxBodies)
                csv.fail(csv.line(), log::cat("column body: a flight holds at most ", kMaxBodies, " bodies"));
            body = f.body_index(name);
        }
        s.body = static_cast<std::uint16_t>(body);
        for (std::size_t i = 0; i < 3; ++i) s.p[i] = csv.number(row[i + 2], i + 2, kPositionRange);
        for (std::size_t i = 0; i < 4; ++i) s.q[i] = csv.number(row[i + 5], i + 5, kQuaternionRange);
        const double norm = std::sqrt(s.q[0] * s.q[0] + s.q[1] * s.q[1] + s.q[2] * s.q[2] + s.q[3] * s.q[3]);
        if (std::abs(norm - 1.0) > 1e-3) csv.fail(csv.line(), log::cat("quaternion norm ", norm, " is not 1"));
        if (!f.poses.empty() && s.t < f.poses.back().t) {
            csv.fail(csv.line(),
                     log::cat("t = ", row[0], " is earlier than the row before (rows must be sorted by t)"));
        }
        f.poses.push_back(s);
    }
    if (f.poses.empty()) csv.fail(1, "no samples");
    if (f.find_body(f.meta.sufferer) < 0) {
        csv.fail(1, log::cat("the sufferer '", f.meta.sufferer, "' named in meta.json has no pose"));
    }
    for (const auto& n : f.meta.neighbours) {
        if (f.find_body(n) < 0) csv.fail(1, log::cat("neighbour '", n, "' named in meta.json has no pose"));
    }
}

std::vector<Leg> read_legs(const fs::path& root) {
    CsvReader csv(slurp(root / "legs.csv"), (root / "legs.csv").string());
    csv.expect_header({"leg", "t_start", "t_end"});
    std::vector<std::string_view> row;
    std::vector<Leg> legs;
    while (csv.next(row)) {
        Leg l;
        const double id = csv.number(row[0], 0, kLegNumberRange);
        if (id != std::floor(id))
            csv.fail(csv.line(),
                     log::cat("column leg: '", row[0], "' is not a leg number (", kLegNumberRange.describe(), ")"));
        l.leg = static_cast<int>(id);
        l.t_start = csv.number(row[1], 1, kStampRange);
        l.t_end = csv.number(row[2], 2, kStampRange);
        if (l.t_end <= l.t_start) csv.fail(csv.line(), "t_end is not after t_start");
        if (!legs.empty() && l.t_start < legs.back().t_start) csv.fail(csv.line(), "legs must be sorted by t_start");
        legs.push_back(l);
    }
    return legs;
}

}  // namespace

Flight read_flight(const std::string& dir) {
    const fs::path root(dir);
    const auto status = input_status(dir, "flight folder");
    if (!fs::is_directory(status))
        throw InputError(log::cat(dir, ": not a flight folder (",
                                  fs::exists(status) ? "not a directory" : "no such directory", ")"));
    Flight f;
    f.meta = read_meta(root / "meta.json");
    read_wrench(root, f);
    read_poses(root, f);
    if (present((root / "legs.csv").string())) f.legs = read_legs(root);
    require_dense(f, dir);
    if (present((root / "reference.csv").string()) || f.meta.reference) {
        if (!f.meta.reference)
            throw InputError(log::cat((root / "meta.json").string(),
                                      ": field 'reference': missing, but reference.csv is there (what model is it?)"));
        f.reference = read_reference_csv((root / "reference.csv").string(), *f.meta.reference);
    }
    return f;
}

namespace {
void require_body_names(const Meta& m) {
    auto check = [](const std::string& field, const std::string& name) {
        if (const auto problem = body_name_problem(name); !problem.empty())
            throw InputError(log::cat("flight to write: meta.json field '", field, "': a body name: ", problem));
    };
    check("sufferer", m.sufferer);
    for (const auto& n : m.neighbours) check("neighbours", n);
    for (const auto& [name, v] : m.vehicles) check("vehicles", name);
}

std::string meta_text(const Meta& m) {
    require_body_names(m);
    json meta = json::parse(m.extra_json);
    meta["format"] = kFormat;
    meta["sufferer"] = m.sufferer;
    meta["neighbours"] = m.neighbours;
    meta["formation"] = m.formation;
    json vehicles = json::object();
    for (const auto& [name, v] : m.vehicles) {
        vehicles[name] = {{"mass_kg", v.mass_kg},
                          {"rotors", v.rotors},
                          {"prop_radius_m", v.prop_radius_m},
                          {"motor_distance_m", v.motor_distance_m}};
    }
    meta["vehicles"] = vehicles;
    if (m.stand_height_m) meta["stand"] = {{"height_m", *m.stand_height_m}};
    if (m.clock_offset_measured_s) meta[kMeasuredClockOffsetKey] = *m.clock_offset_measured_s;
    if (m.stand_pipeline_delay_s) meta[kStandPipelineDelayKey] = *m.stand_pipeline_delay_s;
    if (m.wrench_source != WrenchSource::stand) meta["wrench_source"] = to_string(m.wrench_source);
    if (!m.moments_measured) meta["moments_measured"] = false;
    if (m.pose_source != PoseSource::motion_capture) meta["pose_source"] = to_string(m.pose_source);
    if (m.reference) meta["reference"] = {{"source", m.reference->source}, {"axes", m.reference->axes}};
    try {
        return meta.dump(2) + "\n";
    } catch (const json::type_error&) {  // a text that is not UTF-8 (from a recording's metadata)
        throw InputError("flight to write: meta.json: a text is not UTF-8");
    }
}

constexpr const char* kQuaternion[] = {"qw", "qx", "qy", "qz"};
constexpr const char* kPosition[] = {"n", "e", "d"};
}  // namespace

FlightWriter::FlightWriter(const std::string& dir) : staged_(dir), root_(staged_.path()) {
    wrench_.emplace((root_ / "wrench.csv").string());
    poses_.emplace((root_ / "poses.csv").string());
    for (const auto& column : wrench_columns()) row_ += (row_.empty() ? "" : ",") + column;
    wrench_->write(row_ + "\n");
    poses_->write("t,body,n,e,d,qw,qx,qy,qz\n");
}

FlightWriter::~FlightWriter() {
    wrench_.reset();  // their temporaries go first, then the staging folder (StagedFolder)
    poses_.reset();
}

void FlightWriter::wrench(const WrenchSample& s) {
    row_.clear();
    {
        Row row(row_, "wrench.csv", ++wrench_rows_ + 1);
        row.number(s.t, 6, "t", kStampRange);
        for (std::size_t a = 0; a < kAxes.size(); ++a) row.number(s.w[a], 6, kAxes[a], axis_range(a));
    }
    wrench_->write(row_);
}

void FlightWriter::pose(double t, const std::string& body, const std::array<double, 3>& p,
                        const std::array<double, 4>& q) {
    row_.clear();
    if (const auto problem = body_name_problem(body); !problem.empty())
        throw InputError(log::cat("flight to write: poses.csv row ", pose_rows_ + 2, " column body: ", problem));
    {
        Row row(row_, "poses.csv", ++pose_rows_ + 1);
        row.number(t, 6, "t", kStampRange);
        row.text(body);
        for (std::size_t k = 0; k < 3; ++k) row.number(p[k], 6, kPosition[k], kPositionRange);
        for (std::size_t k = 0; k < 4; ++k) row.number(q[k], 8, kQuaternion[k], kQuaternionRange);
    }
    poses_->write(row_);
}

void FlightWriter::close(const Meta& meta, const std::optional<std::vector<Leg>>& legs,
                         const std::vector<WrenchSample>& reference) {
    if (meta.reference.has_value() != !reference.empty())
        throw InputError("flight to write: meta.json's reference and the reference samples must come together");
    const std::string reference_text = meta.reference ? reference_csv(reference, *meta.reference) : std::string();
    std::string legs_text = "leg,t_start,t_end\n";
    if (legs) {
        for (std::size_t i = 0; i < legs->size(); ++i) {
            const Leg& leg = (*legs)[i];
            Row row(legs_text, "legs.csv", i + 2);
            row.text(std::to_string(leg.leg));
            row.number(leg.t_start, 6, "t_start", kStampRange);
            row.number(leg.t_end, 6, "t_end", kStampRange);
        }
    }
    const std::string meta_json = meta_text(meta);
    wrench_->commit();
    poses_->commit();
    write_file((root_ / "meta.json").string(), meta_json);
    if (legs) write_file((root_ / "legs.csv").string(), legs_text);
    if (meta.reference) write_file((root_ / "reference.csv").string(), reference_text);
    staged_.commit();
    // A flight written over another: its optional files, if this one has none, would be read as this one's.
    std::error_code ec;
    if (!legs) fs::remove(fs::path(staged_.dir()) / "legs.csv", ec);
    if (!meta.reference) fs::remove(fs::path(staged_.dir()) / "reference.csv", ec);
}

void write_flight(const Flight& f, const std::string& dir) {
    FlightWriter w(dir);
    for (const auto& s : f.wrench) w.wrench(s);
    for (const auto& s : f.poses) w.pose(s.t, f.bodies.at(s.body), s.p, s.q);
    w.close(f.meta, f.legs, f.reference);
}

}  // namespace dw::flight
