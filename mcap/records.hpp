#pragma once
// The MCAP record codec the writer, the reader and recovery share (internal to mcap/): opcodes,
// little-endian fields written and read with bounds checks, the records written twice, the bounds
// a file's claims are held to, and chunk compression.
#include <cstdint>
#include <cstring>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "mcap/mcap.hpp"

struct ZSTD_CCtx_s;

namespace dw::mcap::detail {

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
    void field(const std::string& v) { str(v); }
    void field(std::uint16_t v) { u16(v); }
    void field(std::uint64_t v) { u64(v); }
    // A map: its byte length, then each key and value (Map<string, string> of metadata, Map<uint16,
    // uint64> of a chunk index's offsets and the statistics' channel counts).
    template <class K, class V>
    void map(const std::map<K, V>& m) {
        Out body;
        for (const auto& [k, v] : m) {
            body.field(k);
            body.field(v);
        }
        u32(static_cast<std::uint32_t>(body.s.size()));
        s += body.s;
    }
};

// Record contents that appear twice, in the data section and again in the summary.
std::string encode(const Schema& x);
std::string encode(const Channel& x);

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

inline constexpr std::uint64_t kMaxChunk = 1ull << 30;  // a sanity bound on a chunk's uncompressed size
// What a compressed chunk may claim to hold: any size up to kAnyChunk (the lab writes 1 MiB
// chunks), beyond that at most kMaxRatio times its compressed bytes (recorded CDR compresses
// 3-20:1). A file of fake chunk headers each claiming 1 GiB made recover allocate and zero each.
inline constexpr std::uint64_t kAnyChunk = 8ull << 20;
inline constexpr std::uint64_t kMaxRatio = 100;
// Schema data, per schema and in all (the lab's IDL is a few KB, a ROS bag's a few hundred):
// schemas are written uncompressed, so a compressed chunk of huge schemas grew 7 MB into 528 MB.
inline constexpr std::uint64_t kMaxSchemaBytes = 1ull << 20;
inline constexpr std::uint64_t kMaxSchemaBytesInAll = 16ull << 20;

// Chunk compression that keeps its state between chunks: one zstd context and one output buffer,
// sized and touched for the largest chunk up front and reused. Compressing each chunk with a new
// context and a new buffer allocated and freed a few hundred KB per chunk, in sizes that follow
// the chunks; on a busy machine (late ticks, slow fdatasync: larger chunks) that is the suspected
// reason a recorder's memory rose after its warm-up (docs/BENCHMARKS.md, seventh pass).
class Compressor {
public:
    Compressor(Compression c, std::size_t max_input);
    ~Compressor();
    Compressor(const Compressor&) = delete;
    Compressor& operator=(const Compressor&) = delete;
    // `in` compressed (Compression::none: `in` itself); valid until the next call.
    const std::string& operator()(const std::string& in);

private:
    Compression c_;
    ZSTD_CCtx_s* zstd_ = nullptr;  // zstd.h's ZSTD_CCtx
    std::string out_;
};
// A compressed chunk's records (an uncompressed chunk's are read where they lie: chunk_records).
std::vector<std::uint8_t> decompress(const std::string& compression, std::span<const std::uint8_t> in,
                                     std::uint64_t size, const In& where);

// Throws dw::InputError "<path>: not an MCAP file (...); <consequence>" unless the file (read as
// read_file reads it, with its errors) begins with the MCAP magic.
void require_magic(const std::string& path, const std::string& consequence);

}  // namespace dw::mcap::detail
