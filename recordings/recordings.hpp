#pragma once
// Reading the lab's recordings (MCAP, CDR messages of the lab's IDL types) without joining DDS:
// what `dw-recorder info/export` print and write, and the flight a recording holds, which the
// predictor and the explainer read. Topics and types are the registry's (dds/topics.hpp); the
// recorder's replay, which does publish on DDS, builds on the helpers at the end.
#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <span>
#include <stop_token>
#include <string>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <nlohmann/json.hpp>

#include "dds/topics.hpp"
#include "flight/flight.hpp"
#include "mcap/mcap.hpp"

namespace dw::recordings {

// Messages read between checks of a stop request while exporting.
inline constexpr std::uint64_t kStopCheckEvery = 1024;

// Decodes one recorded CDR message of a lab type (by its scoped name) into JSON; nullopt for a
// type the lab does not know. Throws dw::InputError for bytes that do not decode.
std::optional<nlohmann::json> decode(const std::string& type_name, std::span<const std::uint8_t> cdr);

// Prints topics, counts, rates, duration, losses, metadata and attachments. Returns false when
// the file is damaged (what could be read is still printed, then the problem).
bool print_info(const std::string& path, std::ostream& out);

struct ExportOptions {
    std::string sufferer = flight::kSufferer;  // the rigid body on the stand
    // false: each topic's stamps are moved onto the recorder's clock by its producer's measured
    // clock offset (the median of its heartbeats' clock_offset_s); true: as recorded.
    bool raw_stamps = false;
    std::stop_token stop;  // checked while reading: dw::Stopped, nothing written
    // The streamed flight export holds at most this many rows per topic while it puts them in
    // time order (a recording whose stamps stand still would otherwise be held whole).
    std::size_t reorder_rows = std::size_t{1} << 16;
};
// How a flight export went: whether it had to sort in memory (a topic's stamps stepped back
// behind rows already written), and the most rows one topic's window held.
struct ExportStats {
    bool sorted_in_memory = false;
    std::size_t most_rows_held = 0;
};
// The flight a recording holds, in memory: stand/wrench and mocap/frame (+ the plan's formation),
// the topics named by the registry, on the recorder's clock unless raw_stamps (meta.json's extra
// says which offsets were applied). Throws dw::InputError naming the recording.
flight::Flight flight_from_recording(const std::string& path, const ExportOptions& o);
// That flight written as a flight folder (downwash-flight/1).
ExportStats export_flight(const std::string& path, const std::string& dir, const ExportOptions& o);
// A flight folder as it is, or an .mcap recording's flight (no temporary folder): what the
// analysis tools take. Throws dw::InputError naming the path.
flight::Flight read_flight_or_recording(const std::string& path, const ExportOptions& o = {});
// One CSV per topic: log_time, publish_time and every field in IDL order ("a.b", "a[2].c"), decoded
// straight from the typed message (recordings/csv_export.cpp).
void export_csv(const std::string& path, const std::string& dir, const std::stop_token& stop = {});

// ---- for code that reads a recording message by message ----

// The schemas and channels of a recording, as the reader meets them.
struct Catalogue {
    std::map<std::uint16_t, mcap::Schema> schemas;
    std::map<std::uint16_t, mcap::Channel> channels;
    // Makes h fill this catalogue.
    void watch(mcap::Handlers& h);
    // The scoped type name of a channel's schema ("" without one).
    std::string type_of(const mcap::Channel& c) const;
};

// "rt/<ns>/<suffix>" -> "<suffix>" (the registry's name); other names as they are.
std::string topic_suffix(const std::string& topic);

// Throws dw::InputError naming the file when the read met damage.
void require_sound(const mcap::ReadResult& r, const std::string& path);

// Calls f(spec) with the topic spec whose type has this scoped name; false when no lab type has it.
template <class F>
bool with_type(const std::string& type_name, F&& f) {
    bool found = false;
    dds::topics::for_each([&](const auto& spec) {
        if (!found && spec.type_name == type_name) {
            found = true;
            f(spec);
        }
    });
    return found;
}

// A recorded CDR message into a lab type; false when the bytes do not decode. Read in place, as
// the type's PubSubType reads a payload (building that type support and a payload copy for each
// message was a third of the flight export's time).
template <class T>
bool deserialize(std::span<const std::uint8_t> cdr, T& out) {
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(const_cast<std::uint8_t*>(cdr.data())), cdr.size());
    eprosima::fastcdr::Cdr in(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    try {
        in.read_encapsulation();
        out.deserialize(in);
    } catch (const std::exception&) {
        return false;  // Fast CDR throws NotEnoughMemoryException on short buffers
    }
    return true;
}

}  // namespace dw::recordings
