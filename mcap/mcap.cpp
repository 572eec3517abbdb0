#include "mcap/mcap.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <lz4frame.h>
#include <unistd.h>
#include <isa-l/crc.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <tuple>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/names.hpp"

namespace dw::mcap {

namespace {

enum Op : std::uint8_t {
    kHeader = 0x01,
    kFooter = 0x02,
    kSchema = 0x03,
    kChannel = 0x04,
    kMessage = 0x05,
    kChunk = 0x06,
    kMessageIndex = 0x07,
    kChunkIndex = 0x08,
    kAttachment = 0x09,
    kAttachmentIndex = 0x0A,
    kStatistics = 0x0B,
    kMetadata = 0x0C,
    kMetadataIndex = 0x0D,
    kSummaryOffset = 0x0E,
    kDataEnd = 0x0F,
};

// Appends little-endian fields (MCAP is little-endian throughout).
struct Out {
    std::string s;
    void u8(std::uint8_t v) { s.push_back(static_cast<char>(v)); }
    void u16(std::uint16_t v) { put(&v, 2); }
    void u32(std::uint32_t v) { put(&v, 4); }
    void u64(std::uint64_t v) { put(&v, 8); }
    void put(const void* p, std::size_t n) { s.append(static_cast<const char*>(p), n); }
    void str(const std::string& v) {
        u32(static_cast<std::uint32_t>(v.size()));
        s += v;
    }
    void map(const std::map<std::string, std::string>& m) {
        Out body;
        for (const auto& [k, v] : m) {
            body.str(k);
            body.str(v);
        }
        u32(static_cast<std::uint32_t>(body.s.size()));
        s += body.s;
    }
};

// Record contents that appear twice, in the data section and again in the summary.
std::string encode(const Schema& x) {
    Out o;
    o.u16(x.id);
    o.str(x.name);
    o.str(x.encoding);
    o.str(x.data);
    return o.s;
}

std::string encode(const Channel& x) {
    Out o;
    o.u16(x.id);
    o.u16(x.schema_id);
    o.str(x.topic);
    o.str(x.message_encoding);
    o.map(x.metadata);
    return o.s;
}

// Reads fields with bounds checks; every problem names the file offset.
class In {
public:
    In(const std::uint8_t* p, std::size_t n, std::uint64_t base) : p_(p), n_(n), base_(base) {}
    std::uint8_t u8() { return get<std::uint8_t>(); }
    std::uint16_t u16() { return get<std::uint16_t>(); }
    std::uint32_t u32() { return get<std::uint32_t>(); }
    std::uint64_t u64() { return get<std::uint64_t>(); }
    std::string str() {
        const std::uint32_t len = u32();
        need(len, "string");
        std::string v(reinterpret_cast<const char*>(p_ + pos_), len);
        pos_ += len;
        return v;
    }
    std::span<const std::uint8_t> bytes(std::uint64_t len, const char* what) {
        need(len, what);
        std::span<const std::uint8_t> v(p_ + pos_, static_cast<std::size_t>(len));
        pos_ += static_cast<std::size_t>(len);
        return v;
    }
    std::span<const std::uint8_t> rest() { return bytes(n_ - pos_, "data"); }
    std::map<std::string, std::string> map() {
        const std::uint32_t len = u32();
        need(len, "map");
        In body(p_ + pos_, len, base_ + pos_);
        pos_ += len;
        std::map<std::string, std::string> m;
        while (body.pos_ < body.n_) {
            std::string k = body.str();
            m[std::move(k)] = body.str();
        }
        return m;
    }
    std::uint64_t offset() const { return base_ + pos_; }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(log::cat("offset ", offset(), ": ", what));
    }

private:
    template <class T>
    T get() {
        need(sizeof(T), "field");
        T v;
        std::memcpy(&v, p_ + pos_, sizeof(T));
        pos_ += sizeof(T);
        return v;
    }
    void need(std::uint64_t len, const char* what) const {
        if (len > n_ - pos_) fail(log::cat(what, " of ", len, " bytes runs past the end of its record"));
    }
    const std::uint8_t* p_;
    std::size_t n_;
    std::size_t pos_ = 0;
    std::uint64_t base_;
};

constexpr std::uint64_t kMaxChunk = 1ull << 30;  // a sanity bound on a chunk's uncompressed size
// What a compressed chunk may claim to hold: any size up to kAnyChunk (the lab writes 1 MiB
// chunks), beyond that at most kMaxRatio times its compressed bytes (recorded CDR compresses
// 3-20:1). A file of fake chunk headers each claiming 1 GiB made recover allocate and zero each.
constexpr std::uint64_t kAnyChunk = 8ull << 20;
constexpr std::uint64_t kMaxRatio = 100;
// Schema data, per schema and in all (the lab's IDL is a few KB, a ROS bag's a few hundred):
// schemas are written uncompressed, so a compressed chunk of huge schemas grew 7 MB into 528 MB.
constexpr std::uint64_t kMaxSchemaBytes = 1ull << 20;
constexpr std::uint64_t kMaxSchemaBytesInAll = 16ull << 20;

std::string compress(Compression c, const std::string& in) {
    if (c == Compression::zstd) {
        std::string out(ZSTD_compressBound(in.size()), '\0');
        const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1);
        if (ZSTD_isError(n)) throw RuntimeError(log::cat("zstd: ", ZSTD_getErrorName(n)));
        out.resize(n);
        return out;
    }
    if (c == Compression::lz4) {
        LZ4F_preferences_t prefs{};
        prefs.frameInfo.contentSize = in.size();
        std::string out(LZ4F_compressFrameBound(in.size(), &prefs), '\0');
        const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
        if (LZ4F_isError(n)) throw RuntimeError(log::cat("lz4: ", LZ4F_getErrorName(n)));
        out.resize(n);
        return out;
    }
    return in;
}

// A compressed chunk's records (an uncompressed chunk's are read where they lie: chunk_records).
std::vector<std::uint8_t> decompress(const std::string& compression, std::span<const std::uint8_t> in,
                                     std::uint64_t size, const In& where) {
    if (size > kMaxChunk)
        where.fail(log::cat("chunk claims ", size, " uncompressed bytes (more than the 1 GiB bound)"));
    if (size > kAnyChunk && size / kMaxRatio > in.size())
        where.fail(log::cat("chunk claims ", size, " uncompressed bytes from ", in.size(), " compressed (more than ",
                            kMaxRatio, ":1)"));
    if (compression == "zstd" && ZSTD_getFrameContentSize(in.data(), in.size()) != size)  // before allocating
        where.fail("zstd chunk: its frame does not hold the size the chunk claims");
    std::vector<std::uint8_t> out(static_cast<std::size_t>(size));
    if (compression == "zstd") {
        const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
        if (ZSTD_isError(n)) where.fail(log::cat("zstd chunk: ", ZSTD_getErrorName(n)));
        if (n != size) where.fail("zstd chunk decompressed to the wrong size");
    } else if (compression == "lz4") {
        LZ4F_dctx* ctx = nullptr;
        LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION);
        std::size_t out_pos = 0, in_pos = 0;
        std::size_t hint = 1;
        while (hint != 0 && in_pos < in.size()) {
            std::size_t out_n = out.size() - out_pos, in_n = in.size() - in_pos;
            hint = LZ4F_decompress(ctx, out.data() + out_pos, &out_n, in.data() + in_pos, &in_n, nullptr);
            if (LZ4F_isError(hint)) {
                LZ4F_freeDecompressionContext(ctx);
                where.fail(log::cat("lz4 chunk: ", LZ4F_getErrorName(hint)));
            }
            out_pos += out_n;
            in_pos += in_n;
            if (out_n == 0 && in_n == 0) break;
        }
        LZ4F_freeDecompressionContext(ctx);
        if (out_pos != size || hint != 0) where.fail("lz4 chunk is truncated or of the wrong size");
    } else {
        where.fail(log::cat("unknown chunk compression '", compression, "'"));
    }
    return out;
}

}  // namespace

std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc) {
    // ISA-L's gzip CRC is the IEEE CRC-32 MCAP uses (reflected 0xEDB88320, init and final xor ~0),
    // continued from `crc` as zlib's crc32 is (Mcap.Crc32IsZlibs checks it against zlib).
    return crc32_gzip_refl(crc, data.data(), data.size());
}

Compression parse_compression(const std::string& text) {
    if (text.empty()) return Compression::none;  // a chunk record's way of saying none
    return parse_name<Compression>(kCompressionNames, text, "compression");
}

std::string to_string(Compression c) { return c == Compression::none ? "" : name_of(kCompressionNames, c); }

// ---------------------------------------------------------------------------------------------
struct Writer::ChunkIndexEntry {
    std::uint64_t start_time, end_time, chunk_offset, chunk_length;
    std::map<std::uint16_t, std::uint64_t> index_offsets;
    std::uint64_t index_length;
    std::string compression;
    std::uint64_t compressed_size, uncompressed_size;

    std::string encode() const {  // the ChunkIndex record's body
        Out o;
        o.u64(start_time);
        o.u64(end_time);
        o.u64(chunk_offset);
        o.u64(chunk_length);
        Out offsets;
        for (const auto& [ch, off] : index_offsets) {
            offsets.u16(ch);
            offsets.u64(off);
        }
        o.u32(static_cast<std::uint32_t>(offsets.s.size()));
        o.s += offsets.s;
        o.u64(index_length);
        o.str(compression);
        o.u64(compressed_size);
        o.u64(uncompressed_size);
        return o.s;
    }
};

Writer::Writer(const std::string& path, const WriterOptions& options) : path_(path), options_(options) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw RuntimeError(log::cat("cannot create ", path, ": ", std::strerror(errno)));
    raw(kMagic, sizeof(kMagic));
    Out h;
    h.str(options_.profile);
    h.str(options_.library);
    record(kHeader, h.s);
}

Writer::~Writer() {
    try {
        close();
    } catch (const std::exception& e) {
        log::error("closing ", path_, ": ", e.what());
    }
}

void Writer::raw(const void* data, std::size_t n) {
    buffer_.append(static_cast<const char*>(data), n);
    if (options_.data_crc || closed_) data_crc_ = crc32({static_cast<const std::uint8_t*>(data), n}, data_crc_);
    offset_ += n;
}

void Writer::write_out(const char* data, std::size_t size) {
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(fd_, data + done, size - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            broken_ = true;
            throw RuntimeError(log::cat("writing ", path_, ": ", std::strerror(errno)));
        }
        done += static_cast<std::size_t>(n);
    }
}

void Writer::record(std::uint8_t opcode, const std::string& content) {
    raw(&opcode, 1);
    const std::uint64_t len = content.size();
    raw(&len, 8);
    raw(content.data(), content.size());
}

std::uint16_t Writer::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
    Schema s{static_cast<std::uint16_t>(schemas_.size() + 1), name, encoding, data};
    record(kSchema, encode(s));
    schemas_.push_back(std::move(s));
    return schemas_.back().id;
}

std::uint16_t Writer::add_channel(const std::string& topic, std::uint16_t schema_id, const std::string& encoding,
                                  const std::map<std::string, std::string>& metadata) {
    Channel c{static_cast<std::uint16_t>(channels_.size() + 1), schema_id, topic, encoding, metadata};
    record(kChannel, encode(c));
    channels_.push_back(std::move(c));
    return channels_.back().id;
}

void Writer::write(const Message& m, std::int64_t now_ns) {
    if (chunk_.empty()) {
        chunk_opened_ns_ = now_ns;
        chunk_start_ = m.log_time;
        chunk_end_ = m.log_time;
    }
    chunk_index_[m.channel_id].emplace_back(m.log_time, chunk_.size());
    const std::uint64_t len = 2 + 4 + 8 + 8 + m.data.size();
    char head[1 + 8 + 2 + 4 + 8 + 8];
    head[0] = static_cast<char>(kMessage);
    std::memcpy(head + 1, &len, 8);
    std::memcpy(head + 9, &m.channel_id, 2);
    std::memcpy(head + 11, &m.sequence, 4);
    std::memcpy(head + 15, &m.log_time, 8);
    std::memcpy(head + 23, &m.publish_time, 8);
    chunk_.append(head, sizeof(head));
    chunk_.append(reinterpret_cast<const char*>(m.data.data()), m.data.size());
    chunk_start_ = std::min(chunk_start_, m.log_time);
    chunk_end_ = std::max(chunk_end_, m.log_time);
    ++message_count_;
    first_time_ = std::min(first_time_, m.log_time);
    last_time_ = std::max(last_time_, m.log_time);
    ++channel_counts_[m.channel_id];
    if (chunk_.size() >= options_.chunk_size) close_chunk();
    else flush_if_due(now_ns);
}

void Writer::flush_if_due(std::int64_t now_ns) {
    if (!chunk_.empty() && now_ns - chunk_opened_ns_ >= static_cast<std::int64_t>(options_.flush_interval_ns)) flush();
}

void Writer::close_chunk() {
    if (chunk_.empty()) return;
    std::string compressed;
    if (options_.compression != Compression::none) compressed = compress(options_.compression, chunk_);
    const std::string& body = options_.compression == Compression::none ? chunk_ : compressed;
    ChunkIndexEntry e;
    e.start_time = chunk_start_;
    e.end_time = chunk_end_;
    e.chunk_offset = offset_;
    e.compression = to_string(options_.compression);
    e.compressed_size = body.size();
    e.uncompressed_size = chunk_.size();
    Out o;
    o.u8(kChunk);
    o.u64(0);  // record length, set below
    o.u64(chunk_start_);
    o.u64(chunk_end_);
    o.u64(chunk_.size());
    o.u32(crc32({reinterpret_cast<const std::uint8_t*>(chunk_.data()), chunk_.size()}));
    o.str(e.compression);
    o.u64(body.size());
    const std::uint64_t len = o.s.size() - 9 + body.size();
    std::memcpy(o.s.data() + 1, &len, 8);
    raw(o.s.data(), o.s.size());
    if (body.size() >= (64u << 10)) {
        // Large bodies go straight to the file: no copy through the buffer.
        write_out(buffer_.data(), buffer_.size());
        buffer_.clear();
        write_out(body.data(), body.size());
        if (options_.data_crc)
            data_crc_ = crc32({reinterpret_cast<const std::uint8_t*>(body.data()), body.size()}, data_crc_);
        offset_ += body.size();
    } else {
        raw(body.data(), body.size());
    }
    e.chunk_length = offset_ - e.chunk_offset;
    const std::uint64_t index_start = offset_;
    for (const auto& [channel, entries] : chunk_index_) {
        e.index_offsets[channel] = offset_;
        Out mi;
        mi.u16(channel);
        mi.u32(static_cast<std::uint32_t>(entries.size() * 16));
        for (const auto& [t, off] : entries) {
            mi.u64(t);
            mi.u64(off);
        }
        record(kMessageIndex, mi.s);
    }
    e.index_length = offset_ - index_start;
    chunk_indexes_.push_back(std::move(e));
    chunk_.clear();
    chunk_index_.clear();
    if (buffer_.size() >= (4u << 20)) {  // keep memory bounded between timed flushes
        write_out(buffer_.data(), buffer_.size());
        buffer_.clear();
    }
}

void Writer::flush() {
    close_chunk();
    write_out(buffer_.data(), buffer_.size());
    buffer_.clear();
    if (options_.fsync) ::fdatasync(fd_);
}

void Writer::add_metadata(const Metadata& m) {
    const std::uint64_t start = offset_;
    Out o;
    o.str(m.name);
    o.map(m.entries);
    record(kMetadata, o.s);
    metadata_index_.emplace_back(start, offset_ - start, m.name);
}

void Writer::add_attachment(const Attachment& a) {
    const std::uint64_t start = offset_;
    Out o;
    o.u64(a.log_time);
    o.u64(a.create_time);
    o.str(a.name);
    o.str(a.media_type);
    o.u64(a.data.size());
    o.s += a.data;
    o.u32(crc32({reinterpret_cast<const std::uint8_t*>(o.s.data()), o.s.size()}));
    record(kAttachment, o.s);
    attachment_index_.emplace_back(start, offset_ - start);
    attachment_meta_.push_back({a.log_time, a.create_time, a.name, a.media_type, std::string()});
    attachment_sizes_.push_back(a.data.size());
}

void Writer::close() {
    if (closed_) return;
    if (broken_) {  // a write failed: its error was thrown then; nothing more is written
        closed_ = true;
        if (fd_ >= 0) ::close(fd_);
        fd_ = -1;
        return;
    }
    close_chunk();
    Out de;
    de.u32(options_.data_crc ? data_crc_ : 0);
    record(kDataEnd, de.s);
    closed_ = true;  // from here raw() always computes the (summary) CRC

    // Summary: groups by opcode, each remembered for its SummaryOffset record.
    const std::uint64_t summary_start = offset_;
    data_crc_ = 0;  // from here it is the summary CRC
    std::vector<std::tuple<std::uint8_t, std::uint64_t, std::uint64_t>> groups;
    auto group = [&](std::uint8_t op, const std::function<void()>& body) {
        const std::uint64_t start = offset_;
        body();
        if (offset_ > start) groups.emplace_back(op, start, offset_ - start);
    };
    group(kSchema, [&] {
        for (const auto& s : schemas_) record(kSchema, encode(s));
    });
    group(kChannel, [&] {
        for (const auto& c : channels_) record(kChannel, encode(c));
    });
    group(kStatistics, [&] { record(kStatistics, statistics()); });
    group(kChunkIndex, [&] {
        for (const auto& e : chunk_indexes_) record(kChunkIndex, e.encode());
    });
    group(kAttachmentIndex, [&] { write_attachment_index(); });
    group(kMetadataIndex, [&] {
        for (const auto& [off, len, name] : metadata_index_) {
            Out o;
            o.u64(off);
            o.u64(len);
            o.str(name);
            record(kMetadataIndex, o.s);
        }
    });
    const std::uint64_t summary_offset_start = offset_;
    for (const auto& [op, start, len] : groups) {
        Out o;
        o.u8(op);
        o.u64(start);
        o.u64(len);
        record(kSummaryOffset, o.s);
    }
    write_footer(summary_start, summary_offset_start, !groups.empty());
}

std::string Writer::statistics() const {
    Out o;
    o.u64(message_count_);
    o.u16(static_cast<std::uint16_t>(schemas_.size()));
    o.u32(static_cast<std::uint32_t>(channels_.size()));
    o.u32(static_cast<std::uint32_t>(attachment_index_.size()));
    o.u32(static_cast<std::uint32_t>(metadata_index_.size()));
    o.u32(static_cast<std::uint32_t>(chunk_indexes_.size()));
    o.u64(message_count_ ? first_time_ : 0);
    o.u64(message_count_ ? last_time_ : 0);
    Out counts;
    for (const auto& [ch, n] : channel_counts_) {
        counts.u16(ch);
        counts.u64(n);
    }
    o.u32(static_cast<std::uint32_t>(counts.s.size()));
    o.s += counts.s;
    return o.s;
}

void Writer::write_attachment_index() {
    for (std::size_t i = 0; i < attachment_index_.size(); ++i) {
        Out o;
        o.u64(attachment_index_[i].first);
        o.u64(attachment_index_[i].second);
        o.u64(attachment_meta_[i].log_time);
        o.u64(attachment_meta_[i].create_time);
        o.u64(attachment_sizes_[i]);
        o.str(attachment_meta_[i].name);
        o.str(attachment_meta_[i].media_type);
        record(kAttachmentIndex, o.s);
    }
}

// Footer: the summary CRC runs from the summary start through summary_offset_start.
void Writer::write_footer(std::uint64_t summary_start, std::uint64_t summary_offset_start, bool has_offsets) {
    const bool has_summary = summary_offset_start > summary_start;
    Out f;
    f.u64(has_summary ? summary_start : 0);
    f.u64(has_offsets ? summary_offset_start : 0);
    const std::uint8_t op = kFooter;
    const std::uint64_t len = 8 + 8 + 4;
    raw(&op, 1);
    raw(&len, 8);
    raw(f.s.data(), f.s.size());
    const std::uint32_t crc = data_crc_;
    raw(&crc, 4);
    raw(kMagic, sizeof(kMagic));
    flush();
    ::close(fd_);
    fd_ = -1;
}

// ---------------------------------------------------------------------------------------------
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
std::uint64_t next_sound_chunk(std::span<const std::uint8_t> file, std::uint64_t from) {
    for (std::uint64_t q = from; q + 9 < file.size(); ++q) {
        if (file[q] != kChunk) continue;
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
            const std::uint64_t next = next_sound_chunk(file_, pos + 1);
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

ReadResult read_file(const std::string& path, const Handlers& handlers) {
    MappedFile file(path);
    return LinearRead(file.bytes(), handlers, ReadMode::strict, [&](std::uint64_t at) { file.release_before(at); })
        .run();
}

bool is_closed(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in || in.tellg() < static_cast<std::streamoff>(2 * sizeof kMagic)) return false;
    char tail[sizeof kMagic];
    in.seekg(-static_cast<std::streamoff>(sizeof kMagic), std::ios::end);
    return in.read(tail, sizeof tail) && std::memcmp(tail, kMagic, sizeof kMagic) == 0;
}

ReadResult recover(const std::string& in_path, const std::string& out_path, const WriterOptions& options,
                   const std::stop_token& stop) {
    MappedFile mapped(in_path);  // the input is checked before any output exists
    const auto bytes = mapped.bytes();
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
        throw InputError(log::cat(in_path, ": not an MCAP file (no MCAP magic at offset 0); nothing to recover"));
    }
    const std::string tmp = log::cat(out_path, ".tmp-", ::getpid());
    try {
        Writer out(tmp, options);
        std::map<std::uint16_t, std::uint16_t> schema_ids, channel_ids;
        Handlers h;
        h.on_schema = [&](const Schema& s) { schema_ids[s.id] = out.add_schema(s.name, s.encoding, s.data); };
        h.on_channel = [&](const Channel& c) {
            const auto schema = schema_ids.find(c.schema_id);
            channel_ids[c.id] = out.add_channel(c.topic, schema == schema_ids.end() ? 0 : schema->second,
                                                c.message_encoding, c.metadata);
        };
        h.on_message = [&](const Message& m) {
            Message copy = m;
            copy.channel_id = channel_ids.at(m.channel_id);  // the reader hands on only messages of known channels
            out.write(copy, 0);
        };
        h.on_metadata = [&](const Metadata& m) { out.add_metadata(m); };
        h.on_attachment = [&](const Attachment& a) { out.add_attachment(a); };
        h.on_progress = [&](std::uint64_t, std::uint64_t) {
            if (stop.stop_requested()) throw Stopped("the recovery");
        };
        const ReadResult r =
            LinearRead(bytes, h, ReadMode::salvage, [&](std::uint64_t at) { mapped.release_before(at); }).run();
        out.close();
        if (::rename(tmp.c_str(), out_path.c_str()) != 0)
            throw RuntimeError(log::cat("cannot write ", out_path, ": ", std::strerror(errno)));
        return r;
    } catch (...) {
        ::unlink(tmp.c_str());
        throw;
    }
}

}  // namespace dw::mcap
