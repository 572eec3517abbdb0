#pragma once
// Recordings written without DDS, as the recorder would store them: channels of lab types,
// messages as CDR. For tests and benchmarks.
#include <string>

#include "mcap/mcap.hpp"
#include "testkit/cdr.hpp"

namespace dw::testkit {

class LabRecording {
public:
    explicit LabRecording(const std::string& path, mcap::Compression compression = mcap::Compression::zstd)
        : writer_(path, options(compression)) {}

    // A channel of the registry's topic, rt/<ns>/<suffix>.
    template <class T>
    std::uint16_t channel(const dds::Topic<T>& spec, const std::string& ns = "lab") {
        const auto schema = writer_.add_schema(std::string(spec.type_name), "omgidl", "");
        return writer_.add_channel("rt/" + ns + "/" + std::string(spec.suffix), schema, "cdr", {});
    }
    template <class T>
    void write(std::uint16_t channel, std::uint32_t seq, std::uint64_t log_time_ns, T& message) {
        writer_.write({channel, seq, log_time_ns, log_time_ns, cdr_of(message)}, 0);
    }
    // Bytes as they are (a damaged message, say).
    void write_bytes(std::uint16_t channel, std::uint32_t seq, std::uint64_t log_time_ns,
                     std::span<const std::uint8_t> bytes) {
        writer_.write({channel, seq, log_time_ns, log_time_ns, bytes}, 0);
    }
    void close() { writer_.close(); }
    std::uint64_t bytes_written() const { return writer_.bytes_written(); }

private:
    static mcap::WriterOptions options(mcap::Compression c) {
        mcap::WriterOptions o;
        o.fsync = false;
        o.compression = c;
        return o;
    }
    mcap::Writer writer_;
};

}  // namespace dw::testkit
