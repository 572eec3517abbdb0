// The MCAP writer and reader: round trips per compression, CRCs, truncation and recovery, and a
// seeded corruption loop (thousands of damaged files: a clear error, never a crash).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cstring>
#include <random>
#include <sys/resource.h>
#include <algorithm>
#include <thread>
#include <zlib.h>

#include "core/errors.hpp"
#include "core/subprocess.hpp"
#include "mcap/mcap.hpp"
#include "support.hpp"

using namespace dw::mcap;

namespace {
std::vector<std::uint8_t> payload(std::uint32_t i) {
    std::vector<std::uint8_t> d(8 + i % 50);
    for (std::size_t k = 0; k < d.size(); ++k) d[k] = static_cast<std::uint8_t>(i * 31 + k);
    return d;
}

// Writes n messages on two channels, a metadata record and an attachment.
void write_sample(const std::string& path, Compression c, std::uint32_t n, std::size_t chunk_size = 4096) {
    WriterOptions o;
    o.compression = c;
    o.chunk_size = chunk_size;
    o.fsync = false;
    o.data_crc = c == Compression::lz4;  // exercised on one of the three
    Writer w(path, o);
    const auto s = w.add_schema("dw::msg::Test", "omgidl", "module dw { module msg { struct Test { long a; }; }; };");
    const auto a = w.add_channel("rt/lab/a", s, "cdr", {{"offered_qos", "RELIABLE"}});
    const auto b = w.add_channel("rt/lab/b", s, "cdr", {});
    w.add_metadata({"recording", {{"host", "test"}, {"run_id", "r1"}}});
    for (std::uint32_t i = 0; i < n; ++i) {
        const auto d = payload(i);
        w.write({i % 3 == 0 ? b : a, i, 1000 + i * 10ull, 900 + i * 10ull, d}, 0);
    }
    w.add_attachment({5, 6, "physics.yaml", "application/yaml", "format: downwash-physics/1\n"});
    w.close();
}

long peak_rss_kb() {
    rusage u{};
    ::getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss;
}

void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes);

std::vector<std::uint8_t> bytes_of(const std::string& path) {
    const std::string s = dw::read_file(path);
    return {s.begin(), s.end()};
}
}  // namespace

// MCAP's CRC (ISA-L's) is zlib's crc32: the same value for every length around its block sizes and
// alignments, and continued from a previous value the same way.
TEST(Mcap, Crc32IsZlibs) {
    std::mt19937 rng(7);
    std::vector<std::uint8_t> data(1 << 20);
    for (auto& b : data) b = static_cast<std::uint8_t>(rng());
    for (std::size_t n : {0, 1, 3, 15, 16, 17, 63, 64, 65, 255, 256, 1000, 4096, 65537, 1 << 20}) {
        for (std::size_t at : {0, 1, 7}) {
            const std::size_t len = std::min(n, data.size() - at);
            const std::span<const std::uint8_t> part(data.data() + at, len);
            const auto expected = static_cast<std::uint32_t>(::crc32(0L, part.data(), static_cast<uInt>(len)));
            ASSERT_EQ(dw::mcap::crc32(part), expected) << n << " bytes at " << at;
            const auto continued = static_cast<std::uint32_t>(::crc32(expected, data.data(), 100));
            ASSERT_EQ(dw::mcap::crc32(std::span<const std::uint8_t>(data.data(), 100), expected), continued);
        }
    }
}

TEST(Mcap, RoundTripsEveryCompression) {
    dw::test::TempDir d;
    for (Compression c : {Compression::none, Compression::zstd, Compression::lz4}) {
        const std::string path = d.file("x" + to_string(c) + ".mcap");
        write_sample(path, c, 1000);
        std::vector<Message> got;
        std::vector<std::vector<std::uint8_t>> data;
        std::vector<Channel> channels;
        std::vector<Metadata> metadata;
        std::vector<Attachment> attachments;
        Handlers h;
        h.on_channel = [&](const Channel& ch) { channels.push_back(ch); };
        h.on_message = [&](const Message& m) {
            got.push_back(m);
            data.emplace_back(m.data.begin(), m.data.end());
        };
        h.on_metadata = [&](const Metadata& m) { metadata.push_back(m); };
        h.on_attachment = [&](const Attachment& a) { attachments.push_back(a); };
        const ReadResult r = read_file(path, h);
        ASSERT_FALSE(r.error) << *r.error;
        EXPECT_TRUE(r.complete);
        ASSERT_EQ(got.size(), 1000u);
        for (std::uint32_t i = 0; i < 1000; ++i) {
            EXPECT_EQ(got[i].sequence, i);
            EXPECT_EQ(got[i].log_time, 1000 + i * 10ull);
            EXPECT_EQ(got[i].publish_time, 900 + i * 10ull);
            EXPECT_EQ(data[i], payload(i));
        }
        ASSERT_EQ(channels.size(), 2u);
        EXPECT_EQ(channels[0].metadata.at("offered_qos"), "RELIABLE");
        ASSERT_EQ(metadata.size(), 1u);
        EXPECT_EQ(metadata[0].entries.at("run_id"), "r1");
        ASSERT_EQ(attachments.size(), 1u);
        EXPECT_EQ(attachments[0].data, "format: downwash-physics/1\n");
    }
}

TEST(Mcap, CompressionShrinksRepetitiveChunks) {
    dw::test::TempDir d;
    write_sample(d.file("n.mcap"), Compression::none, 5000, 1 << 20);
    write_sample(d.file("z.mcap"), Compression::zstd, 5000, 1 << 20);
    write_sample(d.file("l.mcap"), Compression::lz4, 5000, 1 << 20);
    EXPECT_LT(bytes_of(d.file("z.mcap")).size(), bytes_of(d.file("n.mcap")).size() / 2);
    EXPECT_LT(bytes_of(d.file("l.mcap")).size(), bytes_of(d.file("n.mcap")).size());
}

TEST(Mcap, TruncatedFileIsReportedAndRecovered) {
    dw::test::TempDir d;
    write_sample(d.file("full.mcap"), Compression::zstd, 3000, 2048);
    auto bytes = bytes_of(d.file("full.mcap"));
    bytes.resize(bytes.size() * 2 / 3);  // as if the power went out
    std::ofstream(d.file("cut.mcap"), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    std::uint64_t n = 0;
    const ReadResult cut = read_file(d.file("cut.mcap"), {.on_message = [&](const Message&) { ++n; }});
    ASSERT_TRUE(cut.error);
    EXPECT_NE(cut.error->find("truncated"), std::string::npos) << *cut.error;
    EXPECT_FALSE(cut.complete);
    EXPECT_GT(n, 1000u);

    WriterOptions o;
    o.fsync = false;
    const ReadResult rec = recover(d.file("cut.mcap"), d.file("fixed.mcap"), o);
    EXPECT_EQ(rec.messages, n);
    std::vector<std::uint32_t> seqs;
    const ReadResult fixed =
        read_file(d.file("fixed.mcap"), {.on_message = [&](const Message& m) { seqs.push_back(m.sequence); }});
    EXPECT_FALSE(fixed.error);
    EXPECT_TRUE(fixed.complete);
    ASSERT_EQ(seqs.size(), n);
    for (std::uint32_t i = 0; i < seqs.size(); ++i) ASSERT_EQ(seqs[i], i);  // a prefix, nothing skipped
}

TEST(Mcap, CrcMismatchesAreCaught) {
    dw::test::TempDir d;
    write_sample(d.file("none.mcap"), Compression::none, 200, 1 << 20);
    auto bytes = bytes_of(d.file("none.mcap"));
    // Flip a byte inside the (uncompressed) chunk: the chunk CRC must catch it.
    std::size_t at = 0;
    for (std::size_t i = 8; i + 9 < bytes.size();) {
        std::uint64_t len = 0;
        std::memcpy(&len, bytes.data() + i + 1, 8);
        if (bytes[i] == 0x06) {
            at = i + 9 + len - 100;
            break;
        }
        i += 9 + len;
    }
    ASSERT_GT(at, 0u);
    bytes[at] ^= 0x40;
    const ReadResult r = read(bytes, {});
    ASSERT_TRUE(r.error);
    EXPECT_NE(r.error->find("CRC mismatch"), std::string::npos) << *r.error;
}

// Issue 19: read_file streams the file; it reads exactly what a read of the whole file in memory
// reads, and still checks the data section's CRC (carried along as it goes).
TEST(Mcap, StreamedReadEqualsTheInMemoryReadAndChecksTheDataCrc) {
    dw::test::TempDir d;
    write_sample(d.file("crc.mcap"), Compression::lz4, 20000, 2048);  // data_crc on for lz4
    auto bytes = bytes_of(d.file("crc.mcap"));
    std::vector<std::uint32_t> streamed, whole;
    std::vector<std::uint64_t> progress;
    Handlers h{.on_message = [&](const Message& m) { streamed.push_back(m.sequence); }};
    h.on_progress = [&](std::uint64_t done, std::uint64_t size) { progress.push_back(done * 1000 / size); };
    const ReadResult a = read_file(d.file("crc.mcap"), h);
    const ReadResult b = read(bytes, {.on_message = [&](const Message& m) { whole.push_back(m.sequence); }});
    ASSERT_FALSE(a.error) << *a.error;
    ASSERT_FALSE(b.error) << *b.error;
    EXPECT_EQ(streamed, whole);
    EXPECT_EQ(streamed.size(), 20000u);
    EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
    ASSERT_FALSE(progress.empty());
    EXPECT_LE(progress.back(), 1000u);
    // A byte changed outside any chunk (the metadata record has no CRC of its own): only the
    // data section's CRC can tell, streamed or not.
    const std::string host = "test";
    const auto at = std::search(bytes.begin(), bytes.end(), host.begin(), host.end());
    ASSERT_NE(at, bytes.end());
    *at = 'T';
    write_bytes(d.file("bad.mcap"), bytes);
    for (const ReadResult& r : {read_file(d.file("bad.mcap"), {}), read(bytes, {})}) {
        ASSERT_TRUE(r.error);
        EXPECT_NE(r.error->find("data section CRC mismatch"), std::string::npos) << *r.error;
    }
}

// Issue 19: memory stays bounded whatever the file's size (the file is not held in memory).
TEST(Mcap, StreamedReadOfALargeFileKeepsMemoryBounded) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "AddressSanitizer keeps freed memory in quarantine (256 MB by default): peak RSS measures that, "
                    "not the reader";
#endif
    dw::test::TempDir d;
    const std::string path = d.file("large.mcap");
    {
        WriterOptions o;
        o.fsync = false;
        o.compression = Compression::none;  // the file as large as its messages
        Writer w(path, o);
        const auto s = w.add_schema("dw::msg::Test", "omgidl", "");
        const auto ch = w.add_channel("rt/lab/a", s, "cdr", {});
        std::vector<std::uint8_t> big(1 << 20);
        for (std::uint32_t i = 0; i < 320; ++i) {
            std::fill(big.begin(), big.end(), static_cast<std::uint8_t>(i));
            w.write({ch, i, i * 1000ull, i * 1000ull, big}, 0);
        }
        w.close();
    }
    ASSERT_GT(std::filesystem::file_size(path), 300u << 20);
    const long before_kb = peak_rss_kb();
    std::uint64_t sum = 0, n = 0;
    const ReadResult r = read_file(path, {.on_message = [&](const Message& m) {
                                       ++n;
                                       for (std::size_t k = 0; k < m.data.size(); k += 4096)
                                           sum += m.data[k];  // touch every page
                                   }});
    ASSERT_FALSE(r.error) << *r.error;
    EXPECT_EQ(n, 320u);
    EXPECT_GT(sum, 0u);
    const long grew_mb = (peak_rss_kb() - before_kb) / 1024;
    EXPECT_LT(grew_mb, 64) << "peak RSS grew by " << grew_mb << " MB reading a 320 MB file";
}

TEST(Mcap, SurvivesThousandsOfCorruptedAndTruncatedFiles) {
    dw::test::TempDir d;
    std::vector<std::vector<std::uint8_t>> originals;
    for (Compression c : {Compression::none, Compression::zstd, Compression::lz4}) {
        write_sample(d.file("o.mcap"), c, 300, 1024);
        originals.push_back(bytes_of(d.file("o.mcap")));
    }
    std::mt19937_64 rng(20261122);
    int errors = 0, clean = 0;
    for (int trial = 0; trial < 6000; ++trial) {
        auto bytes = originals[static_cast<std::size_t>(trial) % originals.size()];
        const int kind = static_cast<int>(rng() % 5);
        if (kind == 0) {
            bytes.resize(rng() % bytes.size());  // truncation
        } else if (kind == 1) {
            for (int k = 0; k < 1 + static_cast<int>(rng() % 8); ++k)
                bytes[rng() % bytes.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        } else if (kind == 2) {
            // A huge length in a record header: must not allocate or read past the end.
            const std::size_t at = 8 + rng() % (bytes.size() - 17);
            const std::uint64_t big = rng();
            std::memcpy(bytes.data() + at + 1, &big, 8);
        } else if (kind == 3) {
            const std::size_t at = rng() % bytes.size();
            bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at), static_cast<std::size_t>(1 + rng() % 64),
                         static_cast<std::uint8_t>(rng()));
        } else {
            const std::size_t a = rng() % bytes.size(), n = rng() % 200;
            bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(a),
                        bytes.begin() + static_cast<std::ptrdiff_t>(std::min(bytes.size(), a + n)));
        }
        std::uint64_t seen = 0;
        const ReadResult r = read(bytes, {.on_message = [&](const Message& m) { seen += m.data.size(); }});
        // Salvage never keeps less than a strict read and never crashes on the same bytes.
        const ReadResult salvaged = read(bytes, {}, ReadMode::salvage);
        EXPECT_GE(salvaged.messages, r.messages);
        if (r.error) {
            ++errors;
            EXPECT_EQ(r.error->rfind("offset ", 0), 0u) << *r.error;  // says where
            EXPECT_LE(r.valid_until, bytes.size());
        } else {
            ++clean;
        }
    }
    EXPECT_GT(errors, 4000);
    EXPECT_GE(clean, 0);
}

TEST(Mcap, NotAnMcapFile) {
    const std::vector<std::uint8_t> junk = {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'};
    const ReadResult r = read(junk, {});
    ASSERT_TRUE(r.error);
    EXPECT_EQ(*r.error, "offset 0: not an MCAP file (no MCAP magic)");
}

namespace {
// Offsets of the top-level chunk records of a well-formed file.
std::vector<std::size_t> chunk_offsets(const std::vector<std::uint8_t>& bytes) {
    std::vector<std::size_t> at;
    for (std::size_t i = 8; i + 9 < bytes.size();) {
        std::uint64_t len = 0;
        std::memcpy(&len, bytes.data() + i + 1, 8);
        if (bytes[i] == 0x06) at.push_back(i);
        if (bytes[i] == 0x0F) break;  // data end
        i += 9 + len;
    }
    return at;
}

void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::vector<std::uint32_t> sequences(const std::string& path) {
    std::vector<std::uint32_t> seqs;
    const ReadResult r = read_file(path, {.on_message = [&](const Message& m) { seqs.push_back(m.sequence); }});
    EXPECT_FALSE(r.error) << *r.error;
    return seqs;
}
}  // namespace

// Issue 14, finding 4: one flipped byte in chunk 1 recovered 0 of 499 messages.
TEST(McapRecover, KeepsEveryIntactChunkAfterADamagedOne) {
    dw::test::TempDir d;
    write_sample(d.file("full.mcap"), Compression::none, 499, 1024);
    auto bytes = bytes_of(d.file("full.mcap"));
    const auto chunks = chunk_offsets(bytes);
    ASSERT_GT(chunks.size(), 5u);
    bytes[chunks[0] + 9 + 60] ^= 0x40;  // inside the first chunk's records: its CRC no longer matches
    bytes.resize(bytes.size() - 200);   // and the tail is cut, as after a crash
    write_bytes(d.file("bad.mcap"), bytes);
    WriterOptions o;
    o.fsync = false;
    const ReadResult r = recover(d.file("bad.mcap"), d.file("fixed.mcap"), o);
    EXPECT_EQ(r.skipped_regions, 1u);
    ASSERT_GE(r.damage.size(), 1u);
    EXPECT_NE(r.damage[0].find("chunk CRC mismatch"), std::string::npos) << r.damage[0];
    const auto seqs = sequences(d.file("fixed.mcap"));
    EXPECT_EQ(seqs.size(), r.messages);
    EXPECT_GT(seqs.size(), 400u);  // every chunk but the first (a few dozen messages) is kept
    EXPECT_LT(seqs.size(), 499u);
    EXPECT_EQ(seqs.back(), 498u);
}

TEST(McapRecover, ResynchronisesAfterADamagedRecordHeader) {
    dw::test::TempDir d;
    write_sample(d.file("full.mcap"), Compression::zstd, 499, 1024);
    auto bytes = bytes_of(d.file("full.mcap"));
    const auto chunks = chunk_offsets(bytes);
    ASSERT_GT(chunks.size(), 5u);
    const std::uint64_t huge = ~0ULL;
    std::memcpy(bytes.data() + chunks[1] + 1, &huge, 8);  // chunk 2's length: the linear walk is lost
    write_bytes(d.file("bad.mcap"), bytes);
    WriterOptions o;
    o.fsync = false;
    const ReadResult r = recover(d.file("bad.mcap"), d.file("fixed.mcap"), o);
    const auto seqs = sequences(d.file("fixed.mcap"));
    EXPECT_GT(seqs.size(), 400u);
    EXPECT_EQ(seqs.back(), 498u);
    EXPECT_EQ(r.skipped_regions, 1u);
}

TEST(McapRecover, ChecksItsInputBeforeMakingAnyOutput) {
    dw::test::TempDir d;
    std::ofstream(d.file("notes.txt")) << "hello world, not an MCAP file";
    WriterOptions o;
    for (const std::string& in : {d.file("notes.txt"), d.file("missing.mcap"), d.file("")}) {
        EXPECT_THROW(recover(in, d.file("out.mcap"), o), dw::InputError) << in;
        EXPECT_FALSE(std::filesystem::exists(d.file("out.mcap"))) << in;
    }
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(d.file("")), std::filesystem::directory_iterator()), 1);
}

// Issue 43: 12 KB of chunk headers each claiming 1 GiB made recover allocate and zero 1 GiB per
// chunk (minutes, deaf to SIGINT); a compressed chunk of huge schemas grew 7 MB into 528 MB. A
// claim is now checked against what the chunk's bytes can hold before anything is allocated, and
// schema data is bounded.
TEST(McapRecover, RefusesImpossibleChunkSizesAndHugeSchemasBeforeAllocating) {
    dw::test::TempDir d;
    const struct {
        Compression c;
        std::uint64_t claim;
        std::string why;
    } cases[] = {{Compression::zstd, 1ull << 30, "uncompressed bytes from"},
                 {Compression::lz4, 1ull << 30, "uncompressed bytes from"},
                 {Compression::zstd, 4ull << 20, "its frame does not hold the size the chunk claims"}};
    for (const auto& c : cases) {
        write_sample(d.file("full.mcap"), c.c, 499, 1024);
        auto bytes = bytes_of(d.file("full.mcap"));
        const auto chunks = chunk_offsets(bytes);
        ASSERT_GT(chunks.size(), 5u);
        for (std::size_t k = 0; k < chunks.size(); k += 2)
            std::memcpy(bytes.data() + chunks[k] + 9 + 16, &c.claim, 8);  // uncompressed_size
        write_bytes(d.file("bad.mcap"), bytes);
        WriterOptions o;
        o.fsync = false;
        const ReadResult r = recover(d.file("bad.mcap"), d.file("fixed.mcap"), o);
        EXPECT_EQ(r.skipped_regions, (chunks.size() + 1) / 2);
        ASSERT_FALSE(r.damage.empty());
        EXPECT_NE(r.damage[0].find(c.why), std::string::npos) << r.damage[0];
        EXPECT_GT(sequences(d.file("fixed.mcap")).size(), 200u);  // the other chunks are kept
    }
    {
        WriterOptions o;
        o.fsync = false;
        o.compression = Compression::zstd;
        Writer w(d.file("schemas.mcap"), o);
        w.add_schema("big", "omgidl", std::string((1 << 20) + 1, 'x'));
        w.close();
    }
    const ReadResult r = read_file(d.file("schemas.mcap"), {});
    ASSERT_TRUE(r.error);
    EXPECT_NE(r.error->find("schema data of 1048577 bytes (at most 1048576 each"), std::string::npos) << *r.error;
}

TEST(McapRecover, StopsWhenAskedAndLeavesNoOutput) {
    dw::test::TempDir d;
    write_sample(d.file("full.mcap"), Compression::zstd, 499, 1024);
    std::stop_source stop;
    stop.request_stop();
    WriterOptions o;
    o.fsync = false;
    EXPECT_THROW(recover(d.file("full.mcap"), d.file("fixed.mcap"), o, stop.get_token()), dw::Stopped);
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(d.file("")), std::filesystem::directory_iterator()), 1);
}

// Issue 70: `recover` on a file full of false chunk headers (each claiming the rest of the file,
// with a CRC to check it by) ignored SIGINT: the scan for the next sound chunk decompressed and
// checked every candidate without a word. It now reports as it scans, and a stop ends it.
TEST(McapRecover, AStopEndsAScanThroughFalseChunkHeaders) {
    dw::test::TempDir dir;
    const std::string in = dir.file("fake.mcap");
    constexpr std::size_t kSize = 16 << 20, kEvery = 64;
    std::vector<std::uint8_t> bytes(kSize, 0x5a);
    const std::uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
    std::copy(std::begin(magic), std::end(magic), bytes.begin());
    bytes[8] = 0;  // an invalid first record: the salvage scan starts here
    for (std::size_t q = 16; q + 64 < kSize; q += kEvery) {
        bytes[q] = 0x06;  // a chunk
        const std::uint64_t len = kSize - q - 9;
        std::memcpy(&bytes[q + 1], &len, 8);
        const std::uint64_t size = len - 40;  // start, end, uncompressed size
        std::memcpy(&bytes[q + 9 + 16], &size, 8);
        const std::uint32_t crc = 0xdeadbeef;
        std::memcpy(&bytes[q + 9 + 24], &crc, 4);
        const std::uint32_t no_compression = 0;  // compression "": the records are the rest
        std::memcpy(&bytes[q + 9 + 28], &no_compression, 4);
        std::memcpy(&bytes[q + 9 + 32], &size, 8);  // the records' length: every byte to the end, CRC'd
    }
    std::ofstream(in, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    std::stop_source stop;
    std::jthread stopper([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        stop.request_stop();
    });
    dw::mcap::WriterOptions wo;
    wo.fsync = false;
    EXPECT_THROW(dw::mcap::recover(in, dir.file("out.mcap"), wo, stop.get_token()), dw::Stopped);
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.mcap")));
}
