#include "mcap/records.hpp"

#include <isa-l/crc.h>
#include <lz4frame.h>
#include <zstd.h>

#include "core/names.hpp"

namespace dw::mcap {
namespace detail {

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

namespace {
constexpr int kZstdLevel = 1;
LZ4F_preferences_t lz4_preferences(std::size_t size) {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = size;
    return prefs;
}
std::size_t compress_bound(Compression c, std::size_t size) {
    switch (c) {
        case Compression::zstd: return ZSTD_compressBound(size);
        case Compression::lz4: {
            const LZ4F_preferences_t prefs = lz4_preferences(size);
            return LZ4F_compressFrameBound(size, &prefs);
        }
        case Compression::none: break;
    }
    return 0;
}
}  // namespace

Compressor::Compressor(Compression c, std::size_t max_input) : c_(c) {
    if (c_ == Compression::zstd) {
        zstd_ = ZSTD_createCCtx();
        if (!zstd_) throw RuntimeError("zstd: cannot create a compression context");
    }
    // Sized and touched now (resize writes every byte; the capacity stays), and the context's
    // workspace allocated by compressing as much once: resident from the start.
    out_.resize(compress_bound(c_, max_input));
    if (c_ != Compression::none) (*this)(std::string(max_input, '\0'));
    out_.clear();
}

Compressor::~Compressor() { ZSTD_freeCCtx(zstd_); }

const std::string& Compressor::operator()(const std::string& in) {
    if (c_ == Compression::none) return in;
    out_.resize(compress_bound(c_, in.size()));
    std::size_t n = 0;
    if (c_ == Compression::zstd) {
        n = ZSTD_compressCCtx(zstd_, out_.data(), out_.size(), in.data(), in.size(), kZstdLevel);
        if (ZSTD_isError(n)) throw RuntimeError(log::cat("zstd: ", ZSTD_getErrorName(n)));
    } else {
        const LZ4F_preferences_t prefs = lz4_preferences(in.size());
        n = LZ4F_compressFrame(out_.data(), out_.size(), in.data(), in.size(), &prefs);
        if (LZ4F_isError(n)) throw RuntimeError(log::cat("lz4: ", LZ4F_getErrorName(n)));
    }
    out_.resize(n);
    return out_;
}

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

}  // namespace detail

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

}  // namespace dw::mcap
