#include "recordings/recordings.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <limits>
#include <queue>
#include <iomanip>
#include <ostream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/msg_json.hpp"
#include "dds/time.hpp"
#include "physics/plausible.hpp"

namespace dw::recordings {
namespace {

// How far behind a topic's latest stamp the flight export still puts a row in order (a producer's
// stamps arrive in order but for jitter; a clock stepping back further makes the export sort in memory).
constexpr double kReorderWindowS = 2.0;

// The process that stamps a topic (the lab's processes are named after their roles).
template <class T>
std::string producer_of(const dds::Topic<T>& spec) {
    for (const auto& r : dds::kRoles)
        if (dds::has(spec.producers, r.role)) return std::string(r.name);
    return "";
}

// Each process's clock offsets as its heartbeats stated them (measured ones only).
using Offsets = std::map<std::string, std::vector<double>>;
double median(std::vector<double> v) {  // v not empty
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}
std::optional<double> median_offset(const Offsets& offsets, const std::string& process) {
    const auto it = offsets.find(process);
    if (it == offsets.end() || it->second.empty()) return std::nullopt;
    return median(it->second);
}

// What the lab's time service measured, for meta.json's extra: each producer's median offset.
nlohmann::json measured_clocks(const std::optional<double>& stand, const std::optional<double>& mocap,
                               const std::string& stand_name, const std::string& mocap_name) {
    nlohmann::json j{{"clock_offsets_measured_s", nlohmann::json::object()}};
    if (stand) j["clock_offsets_measured_s"][stand_name] = *stand;
    if (mocap) j["clock_offsets_measured_s"][mocap_name] = *mocap;
    return j;
}

}  // namespace

void Catalogue::watch(mcap::Handlers& h) {
    h.on_schema = [this](const mcap::Schema& s) { schemas[s.id] = s; };
    h.on_channel = [this](const mcap::Channel& c) { channels[c.id] = c; };
}

std::string Catalogue::type_of(const mcap::Channel& c) const {
    const auto it = c.schema_id ? schemas.find(c.schema_id) : schemas.end();
    return it == schemas.end() ? "" : it->second.name;
}

std::string topic_suffix(const std::string& topic) {
    if (topic.rfind("rt/", 0) != 0) return topic;
    const auto slash = topic.find('/', 3);
    return slash == std::string::npos ? topic : topic.substr(slash + 1);
}

void require_sound(const mcap::ReadResult& r, const std::string& path) {
    if (r.error) {
        throw InputError(log::cat(path, ": ", *r.error, " (dw-recorder recover can rebuild a damaged file)"));
    }
}

std::optional<nlohmann::json> decode(const std::string& type_name, std::span<const std::uint8_t> cdr) {
    std::optional<nlohmann::json> out;
    with_type(type_name, [&](const auto& spec) {
        typename std::decay_t<decltype(spec)>::type m;
        if (!deserialize(cdr, m))
            throw InputError(log::cat("a ", type_name, " message of ", cdr.size(), " bytes does not decode"));
        out = dds::to_json(m);
    });
    return out;
}

bool print_info(const std::string& path, std::ostream& out) {
    Catalogue l;
    struct PerChannel {
        std::uint64_t count = 0, first = UINT64_MAX, last = 0, bytes = 0;
    };
    std::map<std::uint16_t, PerChannel> per;
    std::vector<mcap::Metadata> metadata;
    std::vector<std::string> attachments;  // described, not kept: memory stays bounded
    mcap::Handlers h;
    l.watch(h);
    h.on_message = [&](const mcap::Message& m) {
        auto& p = per[m.channel_id];
        ++p.count;
        p.bytes += m.data.size();
        p.first = std::min(p.first, m.log_time);
        p.last = std::max(p.last, m.log_time);
    };
    h.on_metadata = [&](const mcap::Metadata& m) { metadata.push_back(m); };
    h.on_attachment = [&](const mcap::Attachment& a) {
        attachments.push_back(log::cat("attachment ", a.name, " (", a.media_type, ", ", a.data.size(), " bytes)"));
    };
    const auto r = mcap::read_file(path, h);

    std::uint64_t first = UINT64_MAX, last = 0, total = 0;
    for (const auto& [id, p] : per) {
        first = std::min(first, p.first);
        last = std::max(last, p.last);
        total += p.count;
    }
    const double duration = total ? to_seconds(last - first) : 0.0;
    std::map<std::string, std::string> loss;
    for (const auto& m : metadata) {
        if (m.name == "loss") loss = m.entries;
    }
    out << "file:      " << path << (r.complete ? "" : "  (INCOMPLETE)") << "\n";
    out << "messages:  " << total << " in " << fixed(duration, 2) << " s\n";
    // Columns as wide as the longest name (long namespaces make long topics), two spaces apart.
    std::size_t topic_w = 30, type_w = 28;
    for (const auto& [id, c] : l.channels) {
        topic_w = std::max(topic_w, c.topic.size() + 2);
        type_w = std::max(type_w, l.type_of(c).size() + 2);
    }
    const auto tw = static_cast<int>(topic_w), yw = static_cast<int>(type_w);
    out << std::left << std::setw(tw) << "topic" << std::setw(yw) << "type" << std::right << std::setw(9) << "count"
        << std::setw(10) << "rate_hz" << std::setw(12) << "bytes"
        << "  losses\n";
    for (const auto& [id, c] : l.channels) {
        const PerChannel p = per.count(id) ? per.at(id) : PerChannel{};
        const double span = p.count > 1 ? to_seconds(p.last - p.first) : 0.0;
        const std::string type = l.type_of(c);
        out << std::left << std::setw(tw) << c.topic << std::setw(yw) << type << std::right << std::setw(9) << p.count
            << std::setw(10) << fixed(span > 0 ? static_cast<double>(p.count - 1) / span : 0.0, 1) << std::setw(12)
            << p.bytes << "  " << (loss.count(c.topic) ? loss.at(c.topic) : "(not stored)") << "\n";
    }
    for (const auto& m : metadata) {
        if (m.name == "loss") continue;
        out << "metadata " << m.name << ":";
        for (const auto& [k, v] : m.entries) {
            std::string shown = v.size() > 60 ? v.substr(0, 57) + "..." : v;
            std::replace(shown.begin(), shown.end(), '\n', ' ');
            out << " " << k << "=" << shown;
        }
        out << "\n";
    }
    for (const auto& a : attachments) out << a << "\n";
    if (r.error) out << "DAMAGED: " << *r.error << " — `dw-recorder recover` rebuilds what is readable\n";
    return !r.error.has_value();
}

namespace {

struct WrenchRow {
    double t;
    std::array<double, 6> w;
    bool tared;  // false: recorded before the stand's first tare, the hover thrust in it
};
struct PoseRow {
    double t;
    std::string body;
    std::array<double, 3> p;
    std::array<double, 4> q;  // w x y z, not yet normalised
};
// What one pass over a recording finds besides its rows.
struct Found {
    Offsets offsets;                      // per process: the time service's measured clock offsets
    std::vector<double> pipeline_delays;  // the stand's measured pipeline delays (its status)
    std::string formation = "free";
    bool estimated_poses = false;  // a mocap frame carried the vehicles' own estimates (PX4), not motion capture
    std::map<std::string, std::size_t> left_out;   // per topic suffix: rows that are no measurement (measurement())
    std::size_t tared_rows = 0, untared_rows = 0;  // stand/wrench samples after and before the stand's first tare
    // Whether a wrench row goes into the flight. FLIGHT_FORMAT's wrench.csv is tared: the samples a
    // stand published before its first tare carry the hover thrust (several newtons) and are left
    // out. A recording whose stand never tared keeps them all (an untared flight is still a flight),
    // and the export says so.
    bool keeps(const WrenchRow& r) const { return r.tared || tared_rows == 0; }
};
struct RowHandlers {
    std::function<void(WrenchRow&&)> wrench;
    std::function<void(PoseRow&&)> pose;
};

// Whether a row can be a measurement (physics/plausible.hpp): what is not — a garbled or forged
// sample on the wire — is left out of the flight and counted, never the end of the export (one such
// sample in an hour's recording refused the whole flight). Its stamp is not judged here: a
// recording's stamps may be another time's (a replay recorded, a probe's), and a stray one is found
// where the flight is read (its samples per second).
bool measurement(const WrenchRow& r) { return physics::plausible_wrench(r.w); }
bool measurement(const PoseRow& r) {
    return physics::plausible_position(Eigen::Vector3d(r.p[0], r.p[1], r.p[2])) &&
           physics::plausible_orientation(Eigen::Vector4d(r.q[0], r.q[1], r.q[2], r.q[3]));
}

// One recorded message: its rows to the handlers, the plan's formation and the clock measurements
// into `found`; other topics are passed over.
void read_message(Found& found, const RowHandlers& rows, const std::string& suffix, const mcap::Message& m,
                  const std::string& path) {
    namespace topics = dds::topics;
    auto undecodable = [&] { return InputError(log::cat(path, ": a ", suffix, " message does not decode")); };
    if (suffix == topics::stand_wrench.suffix) {
        msg::WrenchStamped w;
        if (!deserialize(m.data, w)) throw undecodable();
        WrenchRow r{to_seconds(dds::from_msg(w.header().stamp())),
                    {w.force_n().x(), w.force_n().y(), w.force_n().z(), w.torque_nm().x(), w.torque_nm().y(),
                     w.torque_nm().z()},
                    w.tared()};
        if (!measurement(r)) {
            ++found.left_out[suffix];
            return;
        }
        ++(r.tared ? found.tared_rows : found.untared_rows);
        rows.wrench(std::move(r));
    } else if (suffix == topics::mocap_frame.suffix) {
        msg::MocapFrame fr;
        if (!deserialize(m.data, fr)) throw undecodable();
        const double t = to_seconds(dds::from_msg(fr.header().stamp()));
        if (fr.pose_source() == msg::POSE_VEHICLE_ESTIMATE) found.estimated_poses = true;
        for (const auto& b : fr.bodies()) {
            PoseRow r{t,
                      b.name(),
                      {b.position_m().x(), b.position_m().y(), b.position_m().z()},
                      {b.orientation().w(), b.orientation().x(), b.orientation().y(), b.orientation().z()}};
            if (measurement(r)) rows.pose(std::move(r));
            else ++found.left_out[suffix];
        }
    } else if (suffix == topics::experiment_plan.suffix) {
        msg::ExperimentPlan p;
        if (deserialize(m.data, p)) found.formation = p.formation();
    } else if (suffix == topics::stand_status.suffix) {
        msg::StandStatus st;
        if (deserialize(m.data, st) && kPipelineDelayRange.contains(st.pipeline_delay_s()))
            found.pipeline_delays.push_back(st.pipeline_delay_s());
    } else if (suffix == topics::process_status.suffix) {
        msg::ProcessStatus st;
        if (deserialize(m.data, st) && st.clock_uncertainty_s() >= 0 &&
            kClockOffsetRange.contains(st.clock_offset_s()))  // no measurement beyond (1e300, NaN)
            found.offsets[st.process()].push_back(st.clock_offset_s());
    }
}

// One pass over the recording, rows to `rows`; a damaged file is refused.
Found read_rows(const std::string& path, const ExportOptions& o, const RowHandlers& rows) {
    Catalogue l;
    Found found;
    mcap::Handlers h;
    l.watch(h);
    std::uint64_t read = 0;
    h.on_message = [&](const mcap::Message& m) {
        if (++read % kStopCheckEvery == 0) throw_if_stopped(o.stop, "the export");
        read_message(found, rows, topic_suffix(l.channels.at(m.channel_id).topic), m, path);
    };
    require_sound(mcap::read_file(path, h), path);
    return found;
}

void require_rows(bool wrench, bool poses, const std::string& path) {
    for (const auto& [some, suffix] :
         {std::pair{wrench, dds::topics::stand_wrench.suffix}, std::pair{poses, dds::topics::mocap_frame.suffix}})
        if (!some) throw InputError(log::cat(path, ": no ", suffix, " messages: nothing to export as a flight"));
}

// Where each topic's stamps go: less its producer's measured offset (unless raw), less the epoch.
struct Clocks {
    std::string stand = producer_of(dds::topics::stand_wrench), mocap = producer_of(dds::topics::mocap_frame);
    std::optional<double> stand_measured, mocap_measured;
    double stand_offset = 0, mocap_offset = 0, epoch = 0;

    Clocks(const Offsets& offsets, const ExportOptions& o)
        : stand_measured(median_offset(offsets, stand)), mocap_measured(median_offset(offsets, mocap)) {
        stand_offset = o.raw_stamps ? 0.0 : stand_measured.value_or(0.0);
        mocap_offset = o.raw_stamps ? 0.0 : mocap_measured.value_or(0.0);
    }
    // Both clocks relative to one epoch (whole seconds, kept in meta.json) from each topic's first stamp.
    void set_epoch(double first_wrench, double first_pose) {
        epoch = std::floor(std::min(first_wrench - stand_offset, first_pose - mocap_offset));
    }
    double wrench_t(double t) const { return t - stand_offset - epoch; }
    double pose_t(double t) const { return t - mocap_offset - epoch; }
};

std::array<double, 4> normalised(const std::array<double, 4>& q) {
    double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (norm == 0) norm = 1;
    return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

// meta.json's word on the rows that are no measurement, said once per topic on stderr too.
nlohmann::json left_out_note(const Found& found, const std::string& path) {
    if (found.left_out.empty()) return nlohmann::json::object();
    nlohmann::json counts = nlohmann::json::object();
    for (const auto& [suffix, n] : found.left_out) {
        log::warn(path, ": left out ", n, " ", suffix, " rows that are no measurement (not finite, beyond ",
                  physics::kMaxPlausiblePositionM, " m, ", physics::kMaxPlausibleForceN, " N or ",
                  physics::kMaxPlausibleTorqueNm, " N·m, or a quaternion that does not normalise)");
        counts[suffix] = n;
    }
    return {{"rows_left_out", counts}};
}

// meta.json's word on the samples from before the stand's tare, said once on stderr too.
nlohmann::json tare_note(const Found& found, const std::string& path) {
    if (found.untared_rows == 0) return nlohmann::json::object();
    if (found.tared_rows == 0) {
        log::warn(path,
                  ": the stand never tared (no stand/wrench sample says tared): wrench.csv holds the hover "
                  "thrust as well as the air's push");
        return {{"wrench_untared", true}};
    }
    log::info(path, ": left out ", found.untared_rows,
              " stand/wrench samples from before the stand's tare (the hover thrust in them)");
    return {{"wrench_untared_rows_left_out", found.untared_rows}};
}

// meta.json of an exported flight: the bodies in first-seen order, the plan's formation and which
// clock offsets were applied.
flight::Meta export_meta(const std::vector<std::string>& bodies, const Found& found, const Clocks& c,
                         const std::string& path, const ExportOptions& o) {
    if (std::find(bodies.begin(), bodies.end(), o.sufferer) == bodies.end())
        throw InputError(log::cat(path, ": no rigid body named '", o.sufferer, "' (use --sufferer)"));
    flight::Meta m;
    m.sufferer = o.sufferer;
    for (const auto& b : bodies) {
        if (b == o.sufferer) continue;
        m.neighbours.push_back(b);
        m.vehicles[b] = flight::VehicleInfo{};
    }
    const bool known = std::find_if(flight::kFormations.begin(), flight::kFormations.end(),
                                    [&](const char* k) { return found.formation == k; }) != flight::kFormations.end();
    m.formation = known ? found.formation : "free";
    if (found.estimated_poses) m.pose_source = flight::PoseSource::estimate;
    nlohmann::json clocks = nlohmann::json::object();
    if (!o.raw_stamps) clocks = {{c.stand, c.stand_offset}, {c.mocap, c.mocap_offset}};
    nlohmann::json extra{
        {"source", path}, {"epoch_unix_s", c.epoch}, {"raw_stamps", o.raw_stamps}, {"clock_offsets_applied_s", clocks}};
    extra.update(measured_clocks(c.stand_measured, c.mocap_measured, c.stand, c.mocap));
    // When both clocks were measured, the stand's against the mocap's (the explainer's clock effect:
    // a force at mocap time t is stamped t + offset by the stand).
    if (c.stand_measured && c.mocap_measured) m.clock_offset_measured_s = *c.stand_measured - *c.mocap_measured;
    if (!found.pipeline_delays.empty()) m.stand_pipeline_delay_s = median(found.pipeline_delays);
    extra.update(tare_note(found, path));
    extra.update(left_out_note(found, path));
    m.extra_json = extra.dump();
    return m;
}

}  // namespace

flight::Flight flight_from_recording(const std::string& path, const ExportOptions& o) {
    std::vector<WrenchRow> wrench;
    std::vector<PoseRow> poses;
    const Found found = read_rows(
        path, o,
        {[&](WrenchRow&& r) { wrench.push_back(std::move(r)); }, [&](PoseRow&& r) { poses.push_back(std::move(r)); }});
    std::erase_if(wrench, [&](const WrenchRow& r) { return !found.keeps(r); });
    require_rows(!wrench.empty(), !poses.empty(), path);
    Clocks c(found.offsets, o);
    // Stable, as the streamed export's window: rows with the same stamp keep their recorded order.
    std::stable_sort(wrench.begin(), wrench.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
    std::stable_sort(poses.begin(), poses.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
    c.set_epoch(wrench.front().t, poses.front().t);
    flight::Flight f;
    for (const auto& r : wrench) f.wrench.push_back({c.wrench_t(r.t), r.w});
    for (const auto& r : poses) f.poses.push_back({c.pose_t(r.t), f.body_index(r.body), r.p, normalised(r.q)});
    for (const auto& body : f.bodies)
        if (const auto problem = flight::body_name_problem(body); !problem.empty())
            throw InputError(log::cat(path, ": a motion-capture body's name: ", problem));
    f.meta = export_meta(f.bodies, found, c, path, o);
    flight::require_dense(f, path);
    return f;
}

namespace {

// A row older than what its topic already released (stamps stepping back further than the window,
// or behind rows the row bound released): the stream cannot put it in order.
struct OutOfWindow {
    std::string topic;
    double step_back_s;
};

// Rows of one topic put back in time order within a window behind the latest stamp seen, and
// within `max_rows` rows (the oldest goes first when more arrive).
template <class Row>
class Reorder {
public:
    Reorder(std::string topic, std::size_t max_rows, std::function<void(const Row&)> release)
        : topic_(std::move(topic)), max_rows_(std::max<std::size_t>(max_rows, 1)), release_(std::move(release)) {}
    void push(Row&& r) {
        if (r.t < released_) throw OutOfWindow{topic_, released_ - r.t};
        latest_ = std::max(latest_, r.t);
        heap_.push({std::move(r), seq_++});
        while (!heap_.empty() && (heap_.top().row.t < latest_ - kReorderWindowS || heap_.size() > max_rows_)) pop();
        most_held_ = std::max(most_held_, heap_.size());
    }
    std::size_t most_held() const { return most_held_; }
    void drain() {
        while (!heap_.empty()) pop();
    }

private:
    struct Item {
        Row row;
        std::uint64_t seq;  // arrival order among equal stamps (a frame's bodies)
        bool operator>(const Item& o) const { return row.t != o.row.t ? row.t > o.row.t : seq > o.seq; }
    };
    void pop() {
        released_ = heap_.top().row.t;
        release_(heap_.top().row);
        heap_.pop();
    }
    std::string topic_;
    std::size_t max_rows_, most_held_ = 0;
    std::function<void(const Row&)> release_;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> heap_;
    double latest_ = -std::numeric_limits<double>::infinity(), released_ = latest_;
    std::uint64_t seq_ = 0;
};

// Two passes, neither holding the flight: the clocks and the first stamps, then the rows in time
// order straight into the folder. Throws OutOfWindow when a topic's stamps step back behind rows
// already written. Returns the most rows one topic's window held.
std::size_t stream_flight(const std::string& path, const std::string& dir, const ExportOptions& o) {
    double first_any = std::numeric_limits<double>::infinity(), first_tared = first_any, first_pose = first_any;
    const Found found = read_rows(path, o,
                                  {[&](WrenchRow&& r) {
                                       first_any = std::min(first_any, r.t);
                                       if (r.tared) first_tared = std::min(first_tared, r.t);
                                   },
                                   [&](PoseRow&& r) { first_pose = std::min(first_pose, r.t); }});
    const double first_wrench = found.tared_rows > 0 ? first_tared : first_any;  // of the rows kept
    require_rows(std::isfinite(first_wrench), std::isfinite(first_pose), path);
    Clocks c(found.offsets, o);
    c.set_epoch(first_wrench, first_pose);
    flight::FlightWriter out(dir);
    std::vector<std::string> bodies;
    Reorder<WrenchRow> wrench(std::string(dds::topics::stand_wrench.suffix), o.reorder_rows, [&](const WrenchRow& r) {
        out.wrench({c.wrench_t(r.t), r.w});
    });
    Reorder<PoseRow> poses(std::string(dds::topics::mocap_frame.suffix), o.reorder_rows, [&](const PoseRow& r) {
        if (std::find(bodies.begin(), bodies.end(), r.body) == bodies.end()) bodies.push_back(r.body);
        out.pose(c.pose_t(r.t), r.body, r.p, normalised(r.q));
    });
    read_rows(path, o,
              {[&](WrenchRow&& r) {
                   if (found.keeps(r)) wrench.push(std::move(r));
               },
               [&](PoseRow&& r) { poses.push(std::move(r)); }});
    wrench.drain();
    poses.drain();
    out.close(export_meta(bodies, found, c, path, o));
    return std::max(wrench.most_held(), poses.most_held());
}

}  // namespace

ExportStats export_flight(const std::string& path, const std::string& dir, const ExportOptions& o) {
    try {
        return {false, stream_flight(path, dir, o)};
    } catch (const OutOfWindow& e) {
        log::warn(path, ": ", e.topic, " stamps step back ", fixed(e.step_back_s, 3),
                  " s behind rows already written (the streamed export reorders within ", kReorderWindowS, " s and ",
                  o.reorder_rows, " rows per topic): sorting the whole flight in memory");
        flight::write_flight(flight_from_recording(path, o), dir);
        return {true, 0};
    }
}

flight::Flight read_flight_or_recording(const std::string& path, const ExportOptions& o) {
    namespace fs = std::filesystem;
    const auto status = input_status(path, "flight folder or recording");
    if (fs::is_directory(status)) return flight::read_flight(path);
    if (!fs::exists(status)) throw InputError(log::cat(path, ": no such flight folder or recording"));
    if (fs::path(path).extension() != ".mcap")
        throw InputError(log::cat(path, ": not a flight folder or an .mcap recording"));
    return flight_from_recording(path, o);
}

}  // namespace dw::recordings
