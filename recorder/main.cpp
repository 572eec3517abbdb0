// dw-recorder: every lab topic to MCAP, and what to do with a recording afterwards.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "recorder/recorder.hpp"
#include "recorder/tools.hpp"
#include "recordings/recordings.hpp"

namespace {

// ---- one struct per subcommand: its options, how it is declared, what it does --------------------

struct RecordCommand final : dw::cli::Command {
    explicit RecordCommand(const dw::dds::ProcessCli& c) : cli(c) {}
    const dw::dds::ProcessCli& cli;
    CLI::App* cmd = nullptr;
    dw::recorder::RecordOptions rec;
    std::string compression = "zstd";
    double flush_s = 1.0, split_mb = 0, duration_s = 0;
    std::vector<std::string> attach;
    bool quiet = false, no_fsync = false, no_commands = false;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("record", "record lab topics (default: all) to an MCAP file");
        cmd->add_option("topics", rec.topics, "topic suffixes (stand/wrench) or full names; default all");
        cmd->add_option("-o,--out", rec.out, "output file (with splitting: <stem>_NNNN.mcap)");
        cmd->add_option("--compression", compression, "zstd (default), lz4 or none");
        cmd->add_option("--flush-interval", flush_s, "seconds: at most this much is lost on a crash")
            ->check(dw::cli::in({0.05, 60, "s"}));
        cmd->add_option("--chunk-size", rec.writer.chunk_size, "bytes of messages per chunk at most")
            ->check(dw::cli::in({1024, 1 << 30, "bytes"}));
        cmd->add_option("--split-size", split_mb, "start a new file after this many MB (0 = never)")
            ->check(dw::cli::in({0, 1e6, "MB"}));
        cmd->add_option("--split-duration", rec.split_seconds, "start a new file after this many seconds (0 = never)")
            ->check(dw::cli::in(dw::kTimeoutRange));
        cmd->add_option("--attach", attach, "NAME=PATH: store a file (stand calibration, physics config)");
        cmd->add_flag("--paused", rec.start_paused, "start paused (resume: RESUME command or SIGUSR1)");
        cmd->add_flag("--no-command-control", no_commands, "record PAUSE/RESUME commands but do not obey them");
        cmd->add_option("--duration", duration_s, "stop after this many seconds (0, the default: until Ctrl-C)")
            ->check(dw::cli::in(dw::kTimeoutRange));
        cmd->add_flag("--no-fsync", no_fsync, "do not fdatasync each chunk (faster, loses more on a power cut)");
        cmd->add_flag("--quiet", quiet, "no live status line");
        cmd->add_flag("--keep-existing", rec.keep_existing,
                      "never overwrite: write the next free <stem>_NNNN.mcap, and recover in place a file a killed "
                      "recorder left unfinished "
                      "(dw-lab run adds it when it restarts a recorder)");
        return cmd;
    }
    // The options as the Recorder takes them; throws dw::InputError on a bad --attach or compression.
    void complete(const dw::dds::DdsConfig& dds) {
        rec.writer.compression = dw::mcap::parse_compression(compression);
        rec.writer.fsync = !no_fsync;
        rec.command_control = !no_commands;
        // Ticks every 50 ms, so a chunk is written out no later than the interval.
        rec.writer.flush_interval_ns = static_cast<std::uint64_t>(dw::from_seconds(std::max(0.0, flush_s - 0.05)));
        rec.split_bytes =
            static_cast<std::uint64_t>(std::ceil(split_mb * 1e6));  // a positive size is never 0 ("never")
        rec.topics = dw::dds::select_topics(rec.topics, dds.ns);
        for (const auto& a : attach) {
            const auto eq = a.find('=');
            if (eq == std::string::npos || eq == 0) throw dw::InputError("--attach '" + a + "': expected NAME=PATH");
            rec.attachments.emplace_back(a.substr(0, eq), a.substr(eq + 1));
        }
    }
    int run() override {
        dw::require_writable_path(rec.out, "--out");
        dw::dds::Participant participant(cli.dds(), "recorder", cli.clock());
        // The recorder's clock stamps every recorded message: the lab's reference clock.
        const dw::dds::ClockReference reference(participant);
        dw::dds::Heartbeat heartbeat(participant);
        heartbeat.set_state(dw::msg::PROC_RUNNING);
        complete(cli.dds());
        dw::recorder::Recorder recorder(participant, rec);
        dw::Shutdown::instance().on_user_signal([&] { recorder.toggle("SIGUSR1"); });
        dw::log::info("recording to ", recorder.files().front(), " (", compression, ", flush every ", flush_s, " s)");
        const auto start = std::chrono::steady_clock::now();
        auto last_status = start;
        while (!dw::Shutdown::instance().wait_for(std::chrono::milliseconds(50))) {
            recorder.tick();
            const auto now = std::chrono::steady_clock::now();
            if (!quiet && now - last_status >= std::chrono::seconds(1)) {
                std::fprintf(stderr, "\r%s   ", recorder.status_line().c_str());
                last_status = now;
            }
            if (duration_s > 0 && now - start >= std::chrono::duration<double>(duration_s)) break;
        }
        if (!quiet) std::fprintf(stderr, "\n");
        recorder.close();
        if (const auto d = recorder.dropped())
            dw::log::warn(d, " messages dropped: more than ", dw::recorder::kMaxPendingBytes >> 20,
                          " MB were waiting for a stalled disk");
        for (const auto& s : recorder.stats()) {
            if (s.lost > 0)
                dw::log::warn(s.topic, ": ", s.lost, " samples lost (gaps in the writers' sequence numbers)");
        }
        for (const auto& f : recorder.files()) std::cout << "wrote " << f << "\n";
        return 0;
    }
};

struct InfoCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    std::string file;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("info", "topics, counts, rates, duration, losses, metadata");
        cmd->add_option("file", file, "MCAP file")->required();
        return cmd;
    }
    int run() override {
        if (!dw::recordings::print_info(file, std::cout)) {
            throw dw::InputError(file + ": damaged (see above); dw-recorder recover rebuilds what is readable");
        }
        return 0;
    }
};

struct RecoverCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    std::string file, out;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("recover", "rebuild a readable file from a truncated or damaged one");
        cmd->add_option("file", file, "damaged MCAP file")->required();
        cmd->add_option("out", out, "recovered file to write")->required();
        return cmd;
    }
    int run() override {
        dw::require_writable_path(out, "recover output");
        dw::mcap::WriterOptions o;
        const auto r = dw::mcap::recover(file, out, o, dw::Shutdown::instance().token());
        std::cout << "recovered " << r.messages << " messages into " << out << "\n";
        for (const auto& problem : r.damage) std::cout << "  lost: " << problem << "\n";
        if (r.skipped_regions > 0 || r.orphaned_messages > 0) {
            std::cout << "  skipped " << r.skipped_regions << " damaged record(s); " << r.orphaned_messages
                      << " message(s) dropped because their channel record was lost\n";
        }
        return 0;
    }
};

struct ExportCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    std::string file, flight_dir, csv_dir;
    dw::recordings::ExportOptions ex;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("export", "export a recording to a flight folder and/or per-topic CSV");
        cmd->add_option("file", file, "MCAP file")->required();
        cmd->add_option("--flight", flight_dir, "flight folder to write (downwash-flight/1)");
        cmd->add_option("--csv", csv_dir, "directory for one CSV per topic");
        cmd->add_option("--sufferer", ex.sufferer, "rigid body on the stand (default sufferer)");
        cmd->add_flag("--raw-stamps", ex.raw_stamps,
                      "flight: keep each topic's stamps as recorded (default: moved onto the recorder's clock by the "
                      "measured clock offsets)");
        return cmd;
    }
    int run() override {
        // Both outputs are checked before either is written.
        if (cmd->count("--flight")) dw::require_output_dir(flight_dir, "--flight");
        if (cmd->count("--csv")) dw::require_output_dir(csv_dir, "--csv");
        if (flight_dir.empty() && csv_dir.empty()) throw dw::InputError("export: give --flight DIR and/or --csv DIR");
        // Both appear, or neither: the flight folder is staged until the CSV is written.
        std::optional<dw::StagedFolder> flight;
        if (!flight_dir.empty()) {
            ex.stop = dw::Shutdown::instance().token();
            flight.emplace(flight_dir);
            dw::recordings::export_flight(file, flight->path(), ex);
        }
        if (!csv_dir.empty()) dw::recordings::export_csv(file, csv_dir, dw::Shutdown::instance().token());
        if (flight) {
            flight->commit();
            std::cout << "flight folder: " << flight_dir << "\n";
        }
        if (!csv_dir.empty()) std::cout << "CSV per topic: " << csv_dir << "\n";
        return 0;
    }
};

struct ReplayCommand final : dw::cli::Command {
    explicit ReplayCommand(const dw::dds::ProcessCli& c) : cli(c) {}
    const dw::dds::ProcessCli& cli;
    CLI::App* cmd = nullptr;
    std::string file;
    dw::recorder::ReplayOptions rp;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("replay", "publish a recording back on DDS with its original timing");
        cmd->add_option("file", file, "MCAP file")->required();
        cmd->add_option("topics", rp.topics, "topic suffixes to replay; default all");
        cmd->add_option("--speed", rp.speed, "x N of the original rate")->check(dw::cli::in({0.01, 1000}));
        cmd->add_option("--wait-readers", rp.wait_readers, "wait for this many readers per topic first")
            ->check(dw::cli::in(dw::dds::kReadersRange));
        cmd->add_flag("--commands", rp.commands,
                      "replay command topics too (setpoints, experiment commands): vehicles listening will move");
        return cmd;
    }
    int run() override {
        dw::dds::Participant participant(cli.dds(), "replay", cli.clock());
        dw::dds::Heartbeat heartbeat(participant);
        heartbeat.set_state(dw::msg::PROC_RUNNING);
        rp.progress = [](double done) {
            std::fprintf(stderr, "\rdw-recorder: replaying %3d %%", static_cast<int>(done * 100));
        };
        rp.stop = dw::Shutdown::instance().token();
        const auto stats = dw::recorder::replay(file, participant, rp);
        std::fprintf(stderr, "\n");
        std::cout << "replayed " << stats.sent << " samples\n";
        if (!stats.left_out.empty())
            std::cout << "left out the command topics " << dw::log::join(stats.left_out)
                      << " (--commands replays them: vehicles listening will move)\n";
        if (stats.refused > 0)
            std::cout << "not published: " << stats.refused << " command samples holding NaN or inf\n";
        return 0;
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli(
        "dw-recorder: record every lab topic to MCAP; inspect, recover, export and replay recordings");
    CLI::App& app = cli.app();
    app.require_subcommand(1);
    RecordCommand record(cli);
    InfoCommand info;
    RecoverCommand recover;
    ExportCommand exp;
    ReplayCommand replay(cli);
    return dw::cli::run_commands(app, {&record, &info, &recover, &exp, &replay}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-recorder", [&] { return run(argc, argv); });
}
