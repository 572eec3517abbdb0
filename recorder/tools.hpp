#pragma once
// What dw-recorder does with a recording: info, export (flight folder, per-topic CSV), replay.
#include <functional>
#include <iosfwd>
#include <optional>
#include <span>
#include <stop_token>
#include <string>

#include <nlohmann/json.hpp>

#include "dds/participant.hpp"
#include "flight/flight.hpp"

namespace dw::recorder {

// Decodes one recorded CDR message of a lab type (by its scoped name) into JSON; nullopt for a
// type the lab does not know. Throws dw::InputError for bytes that do not decode.
std::optional<nlohmann::json> decode(const std::string& type_name, std::span<const std::uint8_t> cdr);

// Prints topics, counts, rates, duration, losses, metadata and attachments. Returns false when
// the file is damaged (what could be read is still printed, then the problem).
bool print_info(const std::string& path, std::ostream& out);

struct ExportOptions {
    std::string sufferer = "sufferer";  // the rigid body on the stand
    std::stop_token stop;               // checked while reading: dw::Stopped, nothing written
};
// A flight folder (downwash-flight/1) from stand/wrench and mocap/frame (+ the plan's formation).
void export_flight(const std::string& path, const std::string& dir, const ExportOptions& o);
// A flight folder as it is, or an .mcap recording exported to one (through a temporary folder)
// and read back: what the analysis tools take. Throws dw::InputError naming the path.
flight::Flight read_flight_or_recording(const std::string& path);
// One CSV per topic: log_time, publish_time and every field (flattened JSON paths).
void export_csv(const std::string& path, const std::string& dir, const std::stop_token& stop = {});

struct ReplayOptions {
    double speed = 1.0;                  // x N
    std::vector<std::string> topics;     // suffixes; empty = all
    int wait_readers = 0;                // wait for this many readers per topic first
    std::function<void(double)> progress;
};
// Publishes the recorded samples back on DDS with their original timing. Returns how many.
std::uint64_t replay(const std::string& path, dds::Participant& p, const ReplayOptions& o);

}  // namespace dw::recorder
