// dw-bench-stream: `dw-recorder info` and `dw-recorder export --csv` on a large recording (2 GB by
// default), each run as a process: wall time, throughput and peak RSS, beside `cat` of the same
// file to /dev/null in the same run (the anchor: reading the bytes and nothing else). The file is
// read once first, so every row reads it from the page cache; each row starts with no earlier output
// on disk or in memory (removed, then a sync), and the
// rows run in rounds (--repeat), each reported by its median.
//   build/bin/dw-bench-stream [--gb 2] [--dir /tmp] [--compression none|lz4|zstd] [--keep] [--repeat 3]
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/subprocess.hpp"
#include "dds/time.hpp"
#include "testkit/mocap.hpp"
#include "testkit/recording.hpp"

extern char** environ;

namespace {

namespace topics = dw::dds::topics;

struct Options {
    double gb = 2.0;
    std::string dir = "/tmp";
    dw::mcap::Compression compression = dw::mcap::Compression::none;
    bool keep = false;
    int repeat = 3;  // rounds of every row; each row's median is reported (the machine is shared)
};

// A lab at full rate: mocap frames of four bodies and four vehicle states at 180 Hz, the stand's
// wrench and cells at 80 Hz, until the file reaches `bytes`. Returns the number of messages.
std::uint64_t write_recording(const std::string& path, std::uint64_t bytes, dw::mcap::Compression c) {
    dw::testkit::LabRecording w(path, c);
    const auto cm = w.channel(topics::mocap_frame), cv = w.channel(topics::vehicle_state);
    const auto cw = w.channel(topics::stand_wrench), cc = w.channel(topics::stand_cells);
    const char* names[] = {"sufferer", "v1", "v2", "v3"};
    std::uint32_t wrench_seq = 0, state_seq = 0;
    for (std::uint32_t i = 0; w.bytes_written() < bytes; ++i) {
        const std::uint64_t t = 1'700'000'000'000'000'000ull + i * 5'555'556ull;
        const double s = i / 180.0;
        dw::msg::MocapFrame f;
        f.header().seq(i);
        f.header().stamp(dw::dds::to_msg(static_cast<dw::Nanos>(t)));  // stamped as the bridge does
        for (int b = 0; b < 4; ++b)
            dw::testkit::add_body(f, names[b], std::sin(s + b), std::cos(s - b), -1.0 - 0.3 * b);
        w.write(cm, i, t, f);
        for (int b = 1; b < 4; ++b) {
            dw::msg::VehicleState v;
            v.vehicle_id(names[b]);
            v.position_m().x(std::sin(s + b));
            v.header().seq(state_seq);
            w.write(cv, state_seq++, t, v);
        }
        if (i * 80 / 180 == wrench_seq) {
            dw::msg::WrenchStamped m;
            m.header().seq(wrench_seq);
            m.header().stamp(dw::dds::to_msg(static_cast<dw::Nanos>(t)));
            m.force_n().z(-0.3 + 0.01 * std::sin(s));
            w.write(cw, wrench_seq, t, m);
            dw::msg::LoadCellFrame cells;
            cells.header().seq(wrench_seq);
            for (int k = 0; k < 8; ++k)
                cells.counts()[static_cast<std::size_t>(k)] = static_cast<std::int32_t>(1000 * std::sin(s + k));
            w.write(cc, wrench_seq++, t, cells);
        }
    }
    w.close();
    return static_cast<std::uint64_t>(state_seq) * 4 / 3 + 2ull * wrench_seq;  // frames = states / 3
}

struct Run {
    double seconds = 0;
    double peak_rss_mb = 0;
    int status = -1;
};

// Runs argv with its stdout drained through a pipe by this process (so `cat` really copies the
// bytes: to /dev/null it may skip them); wall time and the child's peak RSS.
Run measure(const std::vector<std::string>& argv) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    int fds[2];
    if (::pipe(fds) != 0) throw dw::RuntimeError("pipe failed");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    const auto start = std::chrono::steady_clock::now();
    pid_t pid = 0;
    if (posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ) != 0)
        throw dw::RuntimeError("cannot start " + argv[0]);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    std::vector<char> sink(1 << 20);
    while (::read(fds[0], sink.data(), sink.size()) > 0) {}
    ::close(fds[0]);
    int status = 0;
    rusage u{};
    ::wait4(pid, &status, 0, &u);
    Run r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.peak_rss_mb = static_cast<double>(u.ru_maxrss) / 1024.0;
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return r;
}

double median_seconds(std::vector<Run> runs) {
    std::sort(runs.begin(), runs.end(), [](const Run& a, const Run& b) { return a.seconds < b.seconds; });
    const std::size_t n = runs.size();
    return n % 2 ? runs[n / 2].seconds : 0.5 * (runs[n / 2 - 1].seconds + runs[n / 2].seconds);
}

// One row's rounds: the median, fastest and slowest wall time, the largest peak RSS, and the
// first non-zero exit status (0 when every round passed).
struct Summary {
    double median = 0, min = 0, max = 0, peak_rss_mb = 0;
    int status = 0;
};
Summary summarise(const std::vector<Run>& runs) {
    Summary s{median_seconds(runs), runs.front().seconds, runs.front().seconds, 0, 0};
    for (const Run& r : runs) {
        s.min = std::min(s.min, r.seconds);
        s.max = std::max(s.max, r.seconds);
        s.peak_rss_mb = std::max(s.peak_rss_mb, r.peak_rss_mb);
        if (s.status == 0) s.status = r.status;
    }
    return s;
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw dw::InputError(a + " needs a value");
            return argv[++i];
        };
        if (a == "--gb") o.gb = std::stod(next());
        else if (a == "--dir") o.dir = next();
        else if (a == "--compression") o.compression = dw::mcap::parse_compression(next());
        else if (a == "--keep") o.keep = true;
        else if (a == "--repeat") o.repeat = std::stoi(next());
        else throw dw::InputError("unknown option " + a + " (--gb, --dir, --compression, --keep, --repeat)");
    }
    if (!(o.gb > 0 && o.gb <= 64)) throw dw::InputError("--gb: expected (0, 64]");
    if (o.repeat < 1 || o.repeat > 20) throw dw::InputError("--repeat: expected 1..20");
    return o;
}

}  // namespace

int main(int argc, char** argv) try {
    const Options o = parse(argc, argv);
    namespace fs = std::filesystem;
    const std::string file = (fs::path(o.dir) / "dw-bench-stream.mcap").string();
    const std::string csv = (fs::path(o.dir) / "dw-bench-stream-csv").string();
    const std::string flight = (fs::path(o.dir) / "dw-bench-stream-flight").string();
    std::fprintf(stderr, "writing a %.1f GB recording to %s ...\n", o.gb, file.c_str());
    const std::uint64_t messages = write_recording(file, static_cast<std::uint64_t>(o.gb * 1e9), o.compression);
    const double mb = static_cast<double>(fs::file_size(file)) / 1e6;
    const std::string recorder = dw::executable_dir() + "/dw-recorder";
    measure({"cat", file});  // into the page cache: every row below reads it from memory
    struct Row {
        const char* what;
        std::vector<std::string> argv;
        std::string output;  // what it writes ("": nothing)
    };
    const std::vector<Row> rows = {
        {"cat (anchor)", {"cat", file}, ""},
        {"dw-recorder info", {recorder, "info", file}, ""},
        {"dw-recorder export --csv", {recorder, "export", file, "--csv", csv}, csv},
        {"dw-recorder export --flight", {recorder, "export", file, "--flight", flight}, flight},
    };
    std::printf(
        "recording: %.0f MB, %.2f M messages (%s), %s\n\n", mb, static_cast<double>(messages) * 1e-6,
        o.compression == dw::mcap::Compression::none ? "uncompressed" : dw::mcap::to_string(o.compression).c_str(),
        "mocap 4 bodies + 3 vehicle states at 180 Hz, wrench + cells at 80 Hz");
    // Rounds of every row in turn, so the anchor meets the same moments of a shared machine.
    std::vector<std::vector<Run>> runs(rows.size());
    for (int round = 0; round < o.repeat; ++round) {
        for (std::size_t i = 0; i < rows.size(); ++i) {
            // The row's output of the previous round removed, and the recording and the previous
            // row's output on disk, before the clock starts: no row pays for freeing (replacing 1.4 GB
            // of CSV cost 0.7-1.8 s more here) or writing back another's.
            if (!rows[i].output.empty()) fs::remove_all(rows[i].output);
            ::sync();
            runs[i].push_back(measure(rows[i].argv));
        }
    }
    std::printf(
        "| reader | status | wall s: median (min-max of %d) | MB/s of the file | vs cat | peak RSS MB |\n"
        "|---|---|---|---|---|---|\n",
        o.repeat);
    const double cat_seconds = median_seconds(runs[0]);
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const Summary s = summarise(runs[i]);
        std::printf("| %s | %d | %.2f (%.2f-%.2f) | %.0f | %.0f %% | %.1f |\n", rows[i].what, s.status, s.median, s.min,
                    s.max, mb / s.median, 100.0 * cat_seconds / s.median, s.peak_rss_mb);
    }
    std::uint64_t csv_bytes = 0;
    for (const auto& e : fs::directory_iterator(csv)) csv_bytes += fs::file_size(e.path());
    std::uint64_t flight_bytes = 0;
    for (const auto& e : fs::directory_iterator(flight)) flight_bytes += fs::file_size(e.path());
    std::printf("\nCSV written: %.0f MB; flight folder written: %.0f MB\n", static_cast<double>(csv_bytes) / 1e6,
                static_cast<double>(flight_bytes) / 1e6);
    if (!o.keep) {
        fs::remove(file);
        fs::remove_all(csv);
        fs::remove_all(flight);
    }
    return 0;
} catch (const dw::InputError& e) {
    std::fprintf(stderr, "dw-bench-stream: error: %s\n", e.what());
    return 2;
} catch (const std::exception& e) {
    std::fprintf(stderr, "dw-bench-stream: error: %s\n", e.what());
    return 1;
}
