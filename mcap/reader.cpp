// The MCAP reader: records in file order, chunks decompressed and CRC-checked, strict or salvaging
// (resynchronising on the next sound chunk), streamed from a mapped file.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <fstream>
#include <set>

#include "core/files.hpp"
#include "mcap/records.hpp"

namespace dw::mcap {

using namespace detail;

namespace {

struct Reading {
    const Handlers& h;
    std::set<std::uint16_t> schemas, channels;
    std::uint64_t messages = 0;
    bool salvage = false;  // a message of an unknown channel (its record lost) is counted, not fatal
    std::uint64_t orphaned = 0;
    std::uint64_t schema_bytes = 0;  // of the schemas handed on

    void inner_record(std::uint8_t op, In& in) {
        switch (op) {
            case kSchema: {
                Schema s;
                s.id = in.u16();
                s.name = in.str();
                s.encoding = in.str();
                const std::uint32_t n = in.u32();
                if (n > kMaxSchemaBytes || schema_bytes + n > kMaxSchemaBytesInAll)
                    in.fail(log::cat("schema data of ", n, " bytes (at most ", kMaxSchemaBytes, " each, ",
                                     kMaxSchemaBytesInAll, " in all)"));
                const auto d = in.bytes(n, "schema data");
                s.data.assign(reinterpret_cast<const char*>(d.data()), d.size());
                if (s.id == 0) return;  // readers ignore schema id 0
                if (!schemas.insert(s.id).second) return;
                schema_bytes += n;
                if (h.on_schema) h.on_schema(s);
                return;
            }
            case kChannel: {
                Channel c;
                c.id = in.u16();
                c.schema_id = in.u16();
                c.topic = in.str();
                c.message_encoding = in.str();
                c.metadata = in.map();
                if (c.schema_id != 0 && !schemas.count(c.schema_id)) {
                    if (!salvage) in.fail(log::cat("channel ", c.id, " names unknown schema ", c.schema_id));
                    c.schema_id = 0;  // salvage: its schema record was lost; keep the channel and its messages
                }
                if (channels.insert(c.id).second && h.on_channel) h.on_channel(c);
                return;
            }
            case kMessage: {
                Message m;
                m.channel_id = in.u16();
                m.sequence = in.u32();
                m.log_time = in.u64();
                m.publish_time = in.u64();
                m.data = in.rest();
                if (!channels.count(m.channel_id)) {
                    if (!salvage) in.fail(log::cat("message on unknown channel ", m.channel_id));
                    ++orphaned;
                    return;
                }
                ++messages;
                if (h.on_message) h.on_message(m);
                return;
            }
            default: return;  // other records inside a chunk are skipped by their length
        }
    }
};

}  // namespace

namespace {

// A chunk's records, CRC-checked: where they lie in the file when the chunk is uncompressed (no
// copy), else decompressed into `owned`. Throws InputError (located) when unsound.
struct ChunkRecords {
    std::vector<std::uint8_t> owned;
    std::span<const std::uint8_t> records;
};
ChunkRecords chunk_records(In& in) {
    in.u64();
    in.u64();
    const std::uint64_t size = in.u64();
    const std::uint32_t crc = in.u32();
    const std::string compression = in.str();
    const std::uint64_t n = in.u64();
    ChunkRecords c;
    c.records = in.bytes(n, "chunk records");
    if (compression.empty()) {
        if (c.records.size() != size) in.fail("uncompressed chunk size does not match its records");
    } else {
        c.owned = decompress(compression, c.records, size, in);
        c.records = c.owned;
    }
    if (crc != 0 && crc != crc32(c.records)) in.fail("chunk CRC mismatch");
    return c;
}

// The next offset after `from` where a whole chunk with a matching (non-zero) CRC starts, or the
// file's size: where a salvaging read resumes after a record whose header is damaged.
// `progress(q)` is called every kScanReportEvery candidates tried, so that a stop (the handlers'
// on_progress may throw) ends a scan through a file full of false chunk headers, each of which
// can claim the rest of the file (issue 70: `recover` on such a file ignored SIGINT).
constexpr std::uint64_t kScanReportEvery = 64;
std::uint64_t next_sound_chunk(std::span<const std::uint8_t> file, std::uint64_t from,
                               const std::function<void(std::uint64_t)>& progress) {
    std::uint64_t tried = 0;
    for (std::uint64_t q = from; q + 9 < file.size(); ++q) {
        if (file[q] != kChunk) continue;
        if (progress && ++tried % kScanReportEvery == 0) progress(q);
        std::uint64_t len = 0;
        std::memcpy(&len, file.data() + q + 1, 8);
        if (len > file.size() - q - 9 || len < 8 * 3 + 4 + 4 + 8) continue;
        std::uint32_t crc = 0;
        std::memcpy(&crc, file.data() + q + 9 + 24, 4);
        if (crc == 0) continue;  // nothing to confirm it by
        try {
            In in(file.data() + q + 9, static_cast<std::size_t>(len), q + 9);
            chunk_records(in);
            return q;
        } catch (const InputError&) {
        } catch (const std::bad_alloc&) {  // a false candidate claiming a huge size
        }
    }
    return file.size();
}

// The data section's CRC as the Data End record states it, found from the footer without reading
// the file; 0 (nothing to check) when the file does not end in a sound footer.
std::uint32_t stated_data_crc(std::span<const std::uint8_t> file) {
    constexpr std::size_t kFooterRecord = 9 + 8 + 8 + 4, kDataEndRecord = 9 + 4;
    if (file.size() < 8 + kDataEndRecord + kFooterRecord + 8) return 0;
    const std::size_t footer = file.size() - 8 - kFooterRecord;
    if (file[footer] != kFooter) return 0;
    std::uint64_t summary_start = 0;
    std::memcpy(&summary_start, file.data() + footer + 9, 8);
    const std::uint64_t data_end = (summary_start != 0 ? summary_start : footer) - kDataEndRecord;
    if (summary_start > footer || data_end < 8 || file[data_end] != kDataEnd) return 0;
    std::uint32_t crc = 0;
    std::memcpy(&crc, file.data() + data_end + 9, 4);
    return crc;
}

class LinearRead {
public:
    // `consumed(offset)`: nothing before offset will be read again (a mapped file lets it go).
    LinearRead(std::span<const std::uint8_t> file, const Handlers& h, ReadMode mode,
               std::function<void(std::uint64_t)> consumed = {})
        : file_(file),
          h_(h),
          mode_(mode),
          reading_{h, {}, {}, 0, mode == ReadMode::salvage, 0},
          consumed_(std::move(consumed)),
          check_data_crc_(mode == ReadMode::strict && stated_data_crc(file) != 0) {}

    ReadResult run() {
        try {
            if (file_.size() < 8 || std::memcmp(file_.data(), kMagic, 8) != 0) {
                throw InputError("offset 0: not an MCAP file (no MCAP magic)");
            }
            r_.valid_until = 8;
            std::uint64_t pos = 8;
            while (pos != kDone) {
                pos = step(pos);
                if (pos == kDone) break;
                advance_crc(pos);
                if (consumed_) consumed_(pos);
                if (h_.on_progress) h_.on_progress(pos, file_.size());
            }
        } catch (const InputError& e) {
            note(e.what());
        }
        r_.messages = reading_.messages;
        r_.orphaned_messages = reading_.orphaned;
        return r_;
    }

private:
    static constexpr std::uint64_t kDone = ~0ULL;

    // The data section's CRC, carried along as the read goes (the bytes behind may be released).
    void advance_crc(std::uint64_t to) {
        if (!check_data_crc_ || in_summary_ || to <= crc_at_) return;
        data_crc_ =
            crc32(file_.subspan(static_cast<std::size_t>(crc_at_), static_cast<std::size_t>(to - crc_at_)), data_crc_);
        crc_at_ = to;
    }

    void note(const std::string& problem) {
        if (!r_.error) r_.error = problem;
        r_.damage.push_back(problem);
    }

    // One record at pos; returns the next record's offset, or kDone.
    std::uint64_t step(std::uint64_t pos) {
        if (pos == file_.size())
            throw InputError(log::cat("offset ", pos, ": the file ends without a footer (truncated)"));
        if (file_.size() - pos < 9) throw InputError(log::cat("offset ", pos, ": truncated record header"));
        const std::uint8_t op = file_[pos];
        std::uint64_t len = 0;
        std::memcpy(&len, file_.data() + pos + 1, 8);
        if (op == 0 || len > file_.size() - pos - 9) {
            const std::string problem =
                op == 0 ? log::cat("offset ", pos, ": invalid opcode 0")
                        : log::cat("offset ", pos, ": record (opcode 0x", std::hex, static_cast<int>(op), std::dec,
                                   ") of ", len, " bytes runs past the end of the file (truncated)");
            if (mode_ == ReadMode::strict) throw InputError(problem);
            note(problem);
            const std::uint64_t next = next_sound_chunk(file_, pos + 1, [&](std::uint64_t q) {
                if (h_.on_progress) h_.on_progress(q, file_.size());
            });
            if (next == file_.size()) return kDone;
            ++r_.skipped_regions;
            return next;
        }
        In in(file_.data() + pos + 9, static_cast<std::size_t>(len), pos + 9);
        if (op == kFooter) {
            const std::uint64_t end = pos + 9 + len;
            if (file_.size() - end < 8 || std::memcmp(file_.data() + end, kMagic, 8) != 0) {
                throw InputError(log::cat("offset ", end, ": no closing magic after the footer"));
            }
            r_.complete = true;
            r_.valid_until = end + 8;
            return kDone;
        }
        try {
            record(op, in, pos, len);
        } catch (const InputError& e) {
            if (mode_ == ReadMode::strict) throw;
            note(e.what());  // the record's length is sound: skip just this record
            ++r_.skipped_regions;
        }
        if (r_.damage.empty()) r_.valid_until = pos + 9 + len;
        return pos + 9 + len;
    }

    void record(std::uint8_t op, In& in, std::uint64_t pos, std::uint64_t len) {
        (void)len;
        if (op == kDataEnd) {
            const std::uint32_t crc = in.u32();
            advance_crc(pos);
            if (crc != 0 && check_data_crc_ && crc != data_crc_) {
                throw InputError(log::cat("offset ", pos, ": data section CRC mismatch"));
            }
            in_summary_ = true;
            return;
        }
        if (in_summary_) return;
        switch (op) {
            case kSchema:
            case kChannel:
            case kMessage: reading_.inner_record(op, in); break;
            case kChunk: chunk(in); break;
            case kMetadata: {
                Metadata m;
                m.name = in.str();
                m.entries = in.map();
                if (h_.on_metadata) h_.on_metadata(m);
                break;
            }
            case kAttachment: attachment(in, pos); break;
            default: break;  // indexes, statistics, unknown opcodes: skipped by length
        }
    }

    void chunk(In& in) {
        const ChunkRecords chunk = chunk_records(in);
        const std::span<const std::uint8_t> records = chunk.records;
        std::size_t p = 0;
        while (p < records.size()) {
            if (records.size() - p < 9) in.fail("truncated record inside a chunk");
            const std::uint8_t iop = records[p];
            std::uint64_t ilen = 0;
            std::memcpy(&ilen, records.data() + p + 1, 8);
            if (ilen > records.size() - p - 9) in.fail("record inside a chunk runs past the chunk");
            In inner(records.data() + p + 9, static_cast<std::size_t>(ilen), in.offset());
            reading_.inner_record(iop, inner);
            p += 9 + static_cast<std::size_t>(ilen);
        }
    }

    void attachment(In& in, std::uint64_t pos) {
        Attachment a;
        a.log_time = in.u64();
        a.create_time = in.u64();
        a.name = in.str();
        a.media_type = in.str();
        const std::uint64_t n = in.u64();
        const auto d = in.bytes(n, "attachment data");
        const std::uint64_t covered = in.offset() - (pos + 9);
        const std::uint32_t crc = in.u32();
        if (crc != 0 &&
            crc != crc32(file_.subspan(static_cast<std::size_t>(pos + 9), static_cast<std::size_t>(covered)))) {
            in.fail(log::cat("attachment '", a.name, "' CRC mismatch"));
        }
        a.data.assign(reinterpret_cast<const char*>(d.data()), d.size());
        if (h_.on_attachment) h_.on_attachment(a);
    }

    std::span<const std::uint8_t> file_;
    const Handlers& h_;
    ReadMode mode_;
    Reading reading_;
    ReadResult r_;
    bool in_summary_ = false;
    std::function<void(std::uint64_t)> consumed_;
    bool check_data_crc_ = false;
    std::uint64_t crc_at_ = 0;
    std::uint32_t data_crc_ = 0;
};

// A file mapped read-only. The reader hands back the pages behind it, so a file of any size keeps
// about kResidentWindow of itself resident: memory bounded independent of the file's size.
class MappedFile {
public:
    static constexpr std::uint64_t kResidentWindow = 16 << 20;

    explicit MappedFile(const std::string& path) {
        require_readable_file(path, "MCAP file");
        fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        struct stat st {};
        if (fd_ < 0 || ::fstat(fd_, &st) != 0)
            throw InputError(log::cat(path, ": cannot read: ", std::strerror(errno)));
        size_ = static_cast<std::size_t>(st.st_size);
        if (size_ == 0) return;  // nothing to map: the reader reports "not an MCAP file"
        base_ = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
        if (base_ == MAP_FAILED) {
            base_ = nullptr;
            ::close(fd_);
            throw InputError(log::cat(path, ": cannot map: ", std::strerror(errno)));
        }
        ::madvise(base_, size_, MADV_SEQUENTIAL);
    }
    ~MappedFile() {
        if (base_) ::munmap(base_, size_);
        if (fd_ >= 0) ::close(fd_);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    std::span<const std::uint8_t> bytes() const { return {static_cast<const std::uint8_t*>(base_), base_ ? size_ : 0}; }
    // Whole pages below `offset` leave the process (read again from the page cache if needed).
    void release_before(std::uint64_t offset) {
        static const std::uint64_t page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
        const std::uint64_t end = offset / page * page;
        if (!base_ || end < released_ + kResidentWindow) return;
        ::madvise(static_cast<char*>(base_) + released_, end - released_, MADV_DONTNEED);
        released_ = end;
    }

private:
    int fd_ = -1;
    void* base_ = nullptr;
    std::size_t size_ = 0;
    std::uint64_t released_ = 0;
};

}  // namespace

ReadResult read(std::span<const std::uint8_t> file, const Handlers& handlers, ReadMode mode) {
    return LinearRead(file, handlers, mode).run();
}

ReadResult read_file(const std::string& path, const Handlers& handlers, ReadMode mode) {
    MappedFile file(path);
    return LinearRead(file.bytes(), handlers, mode, [&](std::uint64_t at) { file.release_before(at); }).run();
}

void detail::require_magic(const std::string& path, const std::string& consequence) {
    MappedFile file(path);
    const auto bytes = file.bytes();
    if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
        throw InputError(log::cat(path, ": not an MCAP file (no MCAP magic at offset 0); ", consequence));
}

bool is_closed(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in || in.tellg() < static_cast<std::streamoff>(2 * sizeof kMagic)) return false;
    char tail[sizeof kMagic];
    in.seekg(-static_cast<std::streamoff>(sizeof kMagic), std::ios::end);
    return in.read(tail, sizeof tail) && std::memcmp(tail, kMagic, sizeof kMagic) == 0;
}

}  // namespace dw::mcap
