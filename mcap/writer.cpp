// The MCAP writer: records into chunks (compressed, CRC'd, indexed), then the summary and footer.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <functional>
#include <tuple>

#include "core/files.hpp"
#include "mcap/records.hpp"

namespace dw::mcap {

using namespace detail;

namespace {
// Pending file bytes are written out at this size between timed flushes (memory stays bounded);
// a compressed chunk body this large goes straight to the file instead of through the buffer.
constexpr std::size_t kWriteBlock = 4u << 20;
constexpr std::size_t kDirectBody = 64u << 10;
// A chunk closes at the first message that takes it to chunk_size: room for one more message.
// What is made resident up front is bounded (--chunk-size goes to 1 GiB): larger chunks grow as
// they fill, as before.
constexpr std::size_t kChunkSlack = 64u << 10;
constexpr std::size_t kMaxResidentChunk = 8u << 20;
std::size_t resident_chunk(const WriterOptions& o) { return std::min(o.chunk_size + kChunkSlack, kMaxResidentChunk); }
// Reserves `n` bytes of `s` and writes them once, so they are resident from the start.
void reserve_resident(std::string& s, std::size_t n) {
    s.resize(n);
    s.clear();
}
}  // namespace

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
        o.map(index_offsets);
        o.u64(index_length);
        o.str(compression);
        o.u64(compressed_size);
        o.u64(uncompressed_size);
        return o.s;
    }
};

// The buffers a long recording reuses are sized for the largest chunk and touched here, so that a
// busy machine's larger chunks do not raise the writer's memory after its start (seventh pass of
// docs/BENCHMARKS.md: a soak's recorder rose 0.36-0.62 MB/min after its warm-up in fresh clones).
Writer::Writer(const std::string& path, const WriterOptions& options)
    : path_(path),
      options_(options),
      compressor_(std::make_unique<Compressor>(options.compression, resident_chunk(options))) {
    reserve_resident(chunk_, resident_chunk(options_));
    // A block and a small chunk's body and indexes; a large chunk's message indexes may grow it, once
    // (the recorder writes its buffer out at each timed flush, long before it holds a block).
    reserve_resident(buffer_, kWriteBlock + 2 * kDirectBody);
    require_replaceable(path, "recording");
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
    const std::string& body = (*compressor_)(chunk_);
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
    if (body.size() >= kDirectBody) {
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
    if (buffer_.size() >= kWriteBlock) {
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
    o.map(channel_counts_);
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

}  // namespace dw::mcap
