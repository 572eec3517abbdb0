#pragma once
// MCAP (mcap.dev/spec), written from the public specification: a writer with chunking (zstd,
// lz4 frame or none), message indexes, a summary with statistics, metadata and attachments, and
// CRCs; a linear reader that survives corrupt and truncated input; and recovery of a truncated
// file. Records are plain structs; problems are dw::InputError naming the byte offset.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stop_token>
#include <string>
#include <vector>

namespace dw::mcap {

namespace detail {
class Compressor;
}

inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum class Compression { none, zstd, lz4 };
inline constexpr const char* kCompressionNames[] = {"none", "zstd", "lz4"};  // Compression's values in order
Compression parse_compression(const std::string& text);                      // throws dw::InputError
std::string to_string(Compression c);                                        // "", "zstd", "lz4"

struct Schema {
    std::uint16_t id = 0;
    std::string name, encoding;
    std::string data;
};

struct Channel {
    std::uint16_t id = 0;
    std::uint16_t schema_id = 0;
    std::string topic, message_encoding;
    std::map<std::string, std::string> metadata;
};

struct Message {
    std::uint16_t channel_id = 0;
    std::uint32_t sequence = 0;
    std::uint64_t log_time = 0;      // ns
    std::uint64_t publish_time = 0;  // ns
    std::span<const std::uint8_t> data;
};

struct Metadata {
    std::string name;
    std::map<std::string, std::string> entries;
};

struct Attachment {
    std::uint64_t log_time = 0, create_time = 0;
    std::string name, media_type;
    std::string data;
};

struct WriterOptions {
    Compression compression = Compression::zstd;
    std::size_t chunk_size = 1 << 20;                 // close a chunk at this many uncompressed bytes...
    std::uint64_t flush_interval_ns = 1'000'000'000;  // ...or when its first message is this old
    bool fsync = true;                                // fdatasync at each timed flush: survive a power cut
    bool data_crc = false;                            // CRC of the whole data section (0 = not computed, as
                                                      // the reference writer does by default; chunks and
                                                      // attachments always carry theirs)
    std::string library = "downwash-lab";
    std::string profile;  // "" (custom); not ros2: schemas are omgidl
};

// Not thread-safe: callers serialise (the recorder holds one lock).
class Writer {
public:
    // Throws dw::RuntimeError when the file cannot be created.
    Writer(const std::string& path, const WriterOptions& options);
    ~Writer();  // closes if still open (errors are then only logged)
    Writer(const Writer&) = delete;
    Writer& operator=(const Writer&) = delete;

    std::uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
    std::uint16_t add_channel(const std::string& topic, std::uint16_t schema_id, const std::string& message_encoding,
                              const std::map<std::string, std::string>& metadata);
    // `now_ns` (monotonic) drives the flush interval; messages go into the current chunk.
    void write(const Message& m, std::int64_t now_ns);
    void add_metadata(const Metadata& m);
    void add_attachment(const Attachment& a);
    // Writes out the open chunk if it is older than the flush interval.
    void flush_if_due(std::int64_t now_ns);
    void flush();  // writes out the open chunk now
    // Flushes, writes DataEnd, the summary and the footer. Idempotent.
    void close();

    std::uint64_t bytes_written() const { return offset_; }
    // A write to the file failed (its error was thrown then): close() only closes the descriptor.
    bool broken() const { return broken_; }
    std::uint64_t message_count() const { return message_count_; }
    const std::string& path() const { return path_; }

private:
    struct ChunkIndexEntry;
    void raw(const void* data, std::size_t n);
    void write_out(const char* data, std::size_t n);
    void record(std::uint8_t opcode, const std::string& content);
    void close_chunk();
    std::string statistics() const;  // the Statistics record's content
    void write_attachment_index();
    void write_footer(std::uint64_t summary_start, std::uint64_t summary_offset_start, bool has_offsets);

    std::string path_;
    WriterOptions options_;
    int fd_ = -1;
    bool closed_ = false;
    bool broken_ = false;  // a write to the file failed (a full disk): nothing more is written
    std::uint64_t offset_ = 0;
    std::uint32_t data_crc_ = 0;
    std::string buffer_;  // pending file bytes (written in large blocks)

    std::vector<Schema> schemas_;
    std::vector<Channel> channels_;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> attachment_index_;  // offset, length (+ below)
    std::vector<Attachment> attachment_meta_;                                // without their data
    std::vector<std::uint64_t> attachment_sizes_;
    std::vector<std::tuple<std::uint64_t, std::uint64_t, std::string>> metadata_index_;

    std::string chunk_;  // uncompressed records of the open chunk
    std::unique_ptr<detail::Compressor> compressor_;
    std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>>
        chunk_index_;  // channel -> (log_time, offset)
    std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
    std::int64_t chunk_opened_ns_ = 0;
    std::vector<ChunkIndexEntry> chunk_indexes_;

    std::uint64_t message_count_ = 0;
    std::uint64_t first_time_ = UINT64_MAX, last_time_ = 0;
    std::map<std::uint16_t, std::uint64_t> channel_counts_;
};

// What a linear read found. Handlers may be empty.
struct Handlers {
    std::function<void(const Schema&)> on_schema;
    std::function<void(const Channel&)> on_channel;
    std::function<void(const Message&)> on_message;
    std::function<void(const Metadata&)> on_metadata;
    std::function<void(const Attachment&)> on_attachment;
    std::function<void(std::uint64_t done, std::uint64_t size)>
        on_progress;  // after each record: bytes read of the file's
};

struct ReadResult {
    bool complete = false;             // reached a footer and the closing magic
    std::optional<std::string> error;  // the first problem ("offset N: ..."), if any
    std::vector<std::string> damage;   // every problem met (salvage: each one skipped)
    std::uint64_t messages = 0;
    std::uint64_t skipped_regions = 0;    // salvage: damaged records (chunks) skipped
    std::uint64_t orphaned_messages = 0;  // salvage: messages whose channel record was lost
    std::uint64_t valid_until = 0;        // file offset up to which every record was whole and sound
};

// strict: stop at the first problem. salvage (recovery): skip a damaged record whose length is
// sound, resynchronise on the next chunk whose CRC checks out after a damaged record header, and
// keep every intact record after the damage.
enum class ReadMode { strict, salvage };

// Reads every record in file order, decompressing chunks and checking CRCs, and reports the first
// problem; what was read before it (strict) or around it (salvage) has been handed to the handlers.
ReadResult read(std::span<const std::uint8_t> file, const Handlers& handlers, ReadMode mode = ReadMode::strict);
// The same, streamed from the file: memory stays bounded whatever its size (it is mapped and read
// front to back; pages behind the reader are released).
ReadResult read_file(const std::string& path, const Handlers& handlers, ReadMode mode = ReadMode::strict);

// Rebuilds a readable file (indexes, summary, footer) from a truncated or damaged one: every
// whole, sound record is kept, before and after damaged chunks (a salvage read). The input is
// checked first (missing, a directory, not MCAP: dw::InputError, and no output is made); the output
// appears only when complete; a stop request ends it (dw::Stopped) with no output. Returns what
// the read of `in` found.
ReadResult recover(const std::string& in, const std::string& out, const WriterOptions& options,
                   const std::stop_token& stop = {});

// True when the file ends with the closing magic: its writer closed it (a killed writer's file does
// not, and needs recover() to be read).
bool is_closed(const std::string& path);

std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc = 0);

}  // namespace dw::mcap
