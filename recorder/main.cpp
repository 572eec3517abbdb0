// dw-recorder: every lab topic to MCAP, and what to do with a recording afterwards.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "recorder/recorder.hpp"
#include "recorder/tools.hpp"

namespace {

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-recorder: record every lab topic to MCAP; inspect, recover, export and replay recordings");
    CLI::App& app = cli.app();
    app.require_subcommand(1);

    dw::recorder::RecordOptions rec;
    std::string compression = "zstd";
    double flush_s = 1.0, split_mb = 0, duration_s = 0;
    std::vector<std::string> attach;
    bool quiet = false, no_fsync = false;
    auto* record = app.add_subcommand("record", "record lab topics (default: all) to an MCAP file");
    record->add_option("topics", rec.topics, "topic suffixes (stand/wrench) or full names; default all");
    record->add_option("-o,--out", rec.out, "output file (with splitting: <stem>_NNNN.mcap)");
    record->add_option("--compression", compression, "zstd (default), lz4 or none");
    record->add_option("--flush-interval", flush_s, "seconds: at most this much is lost on a crash")->check(dw::cli::in({0.05, 60, "s"}));
    record->add_option("--chunk-size", rec.writer.chunk_size, "bytes of messages per chunk at most")->check(dw::cli::in({1024, 1 << 30, "bytes"}));
    record->add_option("--split-size", split_mb, "start a new file after this many MB (0 = never)")->check(dw::cli::in({0, 1e6, "MB"}));
    record->add_option("--split-duration", rec.split_seconds, "start a new file after this many seconds (0 = never)")->check(dw::cli::in(dw::kTimeoutRange));
    record->add_option("--attach", attach, "NAME=PATH: store a file (stand calibration, physics config)");
    record->add_flag("--paused", rec.start_paused, "start paused (resume: RESUME command or SIGUSR1)");
    bool no_commands = false;
    record->add_flag("--no-command-control", no_commands, "record PAUSE/RESUME commands but do not obey them");
    record->add_option("--duration", duration_s, "stop after this many seconds (0, the default: until Ctrl-C)")->check(dw::cli::in(dw::kTimeoutRange));
    record->add_flag("--no-fsync", no_fsync, "do not fdatasync each chunk (faster, loses more on a power cut)");
    record->add_flag("--quiet", quiet, "no live status line");

    std::string file;
    auto* info = app.add_subcommand("info", "topics, counts, rates, duration, losses, metadata");
    info->add_option("file", file, "MCAP file")->required();

    std::string out;
    auto* recover = app.add_subcommand("recover", "rebuild a readable file from a truncated or damaged one");
    recover->add_option("file", file, "damaged MCAP file")->required();
    recover->add_option("out", out, "recovered file to write")->required();

    std::string flight_dir, csv_dir;
    dw::recorder::ExportOptions ex;
    auto* exp = app.add_subcommand("export", "export a recording to a flight folder and/or per-topic CSV");
    exp->add_option("file", file, "MCAP file")->required();
    exp->add_option("--flight", flight_dir, "flight folder to write (downwash-flight/1)");
    exp->add_option("--csv", csv_dir, "directory for one CSV per topic");
    exp->add_option("--sufferer", ex.sufferer, "rigid body on the stand (default sufferer)");

    dw::recorder::ReplayOptions rp;
    auto* replay = app.add_subcommand("replay", "publish a recording back on DDS with its original timing");
    replay->add_option("file", file, "MCAP file")->required();
    replay->add_option("topics", rp.topics, "topic suffixes to replay; default all");
    replay->add_option("--speed", rp.speed, "x N of the original rate")->check(dw::cli::in({0.01, 1000}));
    replay->add_option("--wait-readers", rp.wait_readers, "wait for this many readers per topic first")->check(dw::cli::in(dw::dds::kReadersRange));

    cli.parse(argc, argv);

    if (info->parsed()) {
        if (!dw::recorder::print_info(file, std::cout)) {
            throw dw::InputError(file + ": damaged (see above); dw-recorder recover rebuilds what is readable");
        }
        return 0;
    }
    if (recover->parsed()) {
        dw::require_writable_path(out, "recover output");
        dw::mcap::WriterOptions o;
        const auto r = dw::mcap::recover(file, out, o);
        std::cout << "recovered " << r.messages << " messages into " << out << "\n";
        for (const auto& problem : r.damage) std::cout << "  lost: " << problem << "\n";
        if (r.skipped_regions > 0 || r.orphaned_messages > 0) {
            std::cout << "  skipped " << r.skipped_regions << " damaged record(s); " << r.orphaned_messages
                      << " message(s) dropped because their channel record was lost\n";
        }
        return 0;
    }
    if (exp->parsed()) {
        // Both outputs are checked before either is written.
        if (exp->count("--flight")) dw::require_output_dir(flight_dir, "--flight");
        if (exp->count("--csv")) dw::require_output_dir(csv_dir, "--csv");
        if (flight_dir.empty() && csv_dir.empty()) throw dw::InputError("export: give --flight DIR and/or --csv DIR");
        if (!flight_dir.empty()) {
            ex.stop = dw::Shutdown::instance().token();
            dw::recorder::export_flight(file, flight_dir, ex);
            std::cout << "flight folder: " << flight_dir << "\n";
        }
        if (!csv_dir.empty()) {
            dw::recorder::export_csv(file, csv_dir, dw::Shutdown::instance().token());
            std::cout << "CSV per topic: " << csv_dir << "\n";
        }
        return 0;
    }

    if (record->parsed()) dw::require_writable_path(rec.out, "--out");
    dw::dds::Participant participant(cli.dds(), record->parsed() ? "recorder" : "replay");
    dw::dds::Heartbeat heartbeat(participant);
    heartbeat.set_state(dw::msg::PROC_RUNNING);
    if (replay->parsed()) {
        rp.progress = [](double done) { std::fprintf(stderr, "\rdw-recorder: replaying %3d %%", static_cast<int>(done * 100)); };
        const auto n = dw::recorder::replay(file, participant, rp);
        std::fprintf(stderr, "\n");
        std::cout << "replayed " << n << " samples\n";
        return 0;
    }

    rec.writer.compression = dw::mcap::parse_compression(compression);
    rec.writer.fsync = !no_fsync;
    rec.command_control = !no_commands;
    // Ticks every 50 ms, so a chunk is written out no later than the interval.
    rec.writer.flush_interval_ns = static_cast<std::uint64_t>(std::max(0.0, flush_s - 0.05) * 1e9);
    rec.split_bytes = static_cast<std::uint64_t>(std::ceil(split_mb * 1e6));  // a positive size is never 0 ("never")
    rec.topics = dw::dds::select_topics(rec.topics, cli.dds().ns);
    for (const auto& a : attach) {
        const auto eq = a.find('=');
        if (eq == std::string::npos || eq == 0) throw dw::InputError("--attach '" + a + "': expected NAME=PATH");
        rec.attachments.emplace_back(a.substr(0, eq), a.substr(eq + 1));
    }
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
    for (const auto& s : recorder.stats()) {
        if (s.lost > 0) dw::log::warn(s.topic, ": ", s.lost, " samples lost (gaps in the writers' sequence numbers)");
    }
    for (const auto& f : recorder.files()) std::cout << "wrote " << f << "\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-recorder", [&] { return run(argc, argv); });
}
