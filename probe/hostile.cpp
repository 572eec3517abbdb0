#include "probe/hostile.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <thread>

#include "core/log.hpp"
#include "dds/px4.hpp"
#include "dds/qos.hpp"
#include "dds/raw.hpp"
#include "dds/topics.hpp"
#include "probe/samples.hpp"
#include "px4_sim/wire.hpp"

namespace dw::probe {

namespace {

constexpr std::size_t kHeaderBytes = 4;    // the CDR encapsulation: id (2 bytes) and options
constexpr std::uint8_t kUnknownId = 0x77;  // encapsulation 0x7777: no CDR reader knows it
constexpr int kGarbageEvery = 4;           // about one 8-byte word in this many replaced

// The absurd values garbage writes, as 8-byte words.
std::array<std::uint64_t, 5> absurd_words() {
    const auto bits = [](double d) {
        std::uint64_t u = 0;
        std::memcpy(&u, &d, sizeof u);
        return u;
    };
    return {bits(std::numeric_limits<double>::quiet_NaN()), bits(std::numeric_limits<double>::infinity()),
            bits(-std::numeric_limits<double>::infinity()), bits(1e300), ~std::uint64_t{0}};
}

template <class T>
std::vector<std::uint8_t> serialized(T m) {
    typename dds::PubSubOf<T>::type ts;
    eprosima::fastrtps::rtps::SerializedPayload_t p(ts.getSerializedSizeProvider(&m)());
    ts.serialize(&m, &p);
    return {p.data, p.data + p.length};
}

// The corruptions a topic gets: garbage only where a decodable sample forges nothing.
template <class Spec>
std::vector<Corruption> corruptions_for(const Spec& t) {
    if (t.command || t.qos != dds::QosProfile::sensor) return {Corruption::encapsulation, Corruption::truncated};
    return {Corruption::encapsulation, Corruption::truncated, Corruption::garbage};
}

// PX4's output topics the lab reads: what a PX4 client sends (zeros but its frames), corrupted as
// the lab's own are. Odometry is a sensor: absurd words too (PX4 estimating 1e300 m). Status and
// acks state and answer: a decodable forgery is for DDS Security to keep out, so only the
// undecodable kinds.
struct Px4Output {
    px4sim::Msg msg;
    const char* type;  // px4_msgs::msg::dds_::<this>_
    bool sensor;
    std::string_view topic(const dds::Px4VersionInfo& v) const {
        switch (msg) {
            case px4sim::Msg::vehicle_status: return v.status_topic;
            case px4sim::Msg::vehicle_command_ack: return v.ack_topic;
            default: return "vehicle_odometry";
        }
    }
};
constexpr std::array<Px4Output, 3> kPx4Outputs{{{px4sim::Msg::vehicle_odometry, "VehicleOdometry", true},
                                                {px4sim::Msg::vehicle_status, "VehicleStatus", false},
                                                {px4sim::Msg::vehicle_command_ack, "VehicleCommandAck", false}}};
constexpr dds::Px4Version kPx4Version = dds::Px4Version::v1_15;

// One round on every PX4 output topic of namespace ns.
void px4_round(dds::RawParticipant& raw, const std::string& ns, std::uint64_t round, std::mt19937_64& rng,
               HostileCounts& sent) {
    const auto& version = dds::px4_version(kPx4Version);
    for (const auto& out : kPx4Outputs) {
        const std::vector<Corruption> kinds =
            out.sensor ? std::vector{Corruption::encapsulation, Corruption::truncated, Corruption::garbage}
                       : std::vector{Corruption::encapsulation, Corruption::truncated};
        const Corruption c = kinds[round % kinds.size()];
        const std::string topic = dds::px4_topic(ns, "out", out.topic(version));
        const auto bytes =
            px4sim::encode(px4sim::msg_def(out.msg, kPx4Version),
                           {{"pose_frame", {dds::px4::kFrameNed}}, {"velocity_frame", {dds::px4::kFrameNed}}});
        raw.publish(topic, log::cat("px4_msgs::msg::dds_::", out.type, "_"), corrupt(bytes, c, rng));
        ++sent[log::cat(topic, " ", kCorruptionNames[static_cast<std::size_t>(c)])];
    }
}

}  // namespace

std::vector<std::uint8_t> corrupt(std::vector<std::uint8_t> b, Corruption c, std::mt19937_64& rng) {
    if (b.size() <= kHeaderBytes) return b;
    switch (c) {
        case Corruption::encapsulation: b[0] = b[1] = kUnknownId; break;
        case Corruption::truncated: {
            const std::size_t body = b.size() - kHeaderBytes;
            b.resize(kHeaderBytes + std::uniform_int_distribution<std::size_t>(0, body / 2)(rng));
            break;
        }
        case Corruption::garbage: {
            const auto words = absurd_words();
            for (std::size_t at = kHeaderBytes; at + 8 <= b.size(); at += 8)
                if (rng() % kGarbageEvery == 0) std::memcpy(&b[at], &words[rng() % words.size()], 8);
            break;
        }
    }
    return b;
}

HostileCounts run_hostile(const dds::DdsConfig& cfg, const HostileOptions& o, std::ostream& out) {
    dds::RawParticipant raw(cfg, "hostile");
    std::mt19937_64 rng(o.seed);
    HostileCounts sent;
    const auto wanted = [&](std::string_view suffix) {
        return o.lab_topics &&
               (o.topics.empty() || std::find(o.topics.begin(), o.topics.end(), suffix) != o.topics.end());
    };
    const auto period = std::chrono::duration<double>(1.0 / o.rate_hz);
    const auto start = std::chrono::steady_clock::now();
    for (std::uint64_t round = 0; !o.stop.stop_requested(); ++round) {
        if (o.seconds > 0 && std::chrono::steady_clock::now() - start >= std::chrono::duration<double>(o.seconds))
            break;
        dds::topics::for_each([&](const auto& t) {
            if (!wanted(t.suffix)) return;
            using T = typename std::decay_t<decltype(t)>::type;
            const auto kinds = corruptions_for(t);
            const Corruption c = kinds[round % kinds.size()];
            const dds::RawWriterSpec spec{dds::writer_qos(t.qos), typename dds::PubSubOf<T>::type().m_isGetKeyDefined};
            raw.publish(log::cat("rt/", cfg.ns, "/", t.suffix), std::string(t.type_name),
                        corrupt(serialized(make_sample<T>(round)), c, rng), spec);
            ++sent[log::cat(t.suffix, " ", kCorruptionNames[static_cast<std::size_t>(c)])];
        });
        for (const auto& ns : o.px4_namespaces) px4_round(raw, ns, round, rng, sent);
        std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                  static_cast<double>(round + 1) * period));
    }
    for (const auto& [what, n] : sent) out << what << ": " << n << "\n";
    return sent;
}

}  // namespace dw::probe
