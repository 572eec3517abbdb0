// CLI fuzz harness (issue 14): every tool and subcommand started with a table of hostile values in
// its numeric and path options (docs/HOSTILE_INPUT.md lists them and what each tool does). Every
// run must keep the house rules:
//   - exit status 0, 1, 2 or 130; a run still going after its row's bound gets SIGINT and must end
//     within 10 s with 130 (or 0, for rows whose normal end is a stop: Row::until_stopped);
//   - on 2, exactly one non-empty line on stderr: "<tool>: error: ..."; on 1, exactly one such
//     error line (after any progress lines of the work done);
//   - a value that is no number (nan, inf, -inf, "", x) is refused with 2;
//   - an empty path for an option without a default is refused with 2;
//   - no text file the run leaves contains a NaN or inf token;
//   - on 1 and 2: the row's outputs do not exist and an attacked output path is as it was; on any
//     status no "*.tmp-*" file is left (a stop, 130, may leave whole files, never partial ones).
// Tool.StopsWhenAsked interrupts each row's valid base command early with the same checks.
//
// Registration: tests/CMakeLists.txt (dw_fuzz_cli_tests). gtest_discover_tests makes one CTest test
// per row and test (FuzzCli/Tool.HostileValues/sim_fly, FuzzCli/Tool.StopsWhenAsked/sim_fly, ...);
// each test process makes the fixtures its row needs, once. The rows mostly wait on the tools they
// start (CPU class realtime); the predictor's training rows keep one thread busy (class thread).
// FuzzCli gives each numeric option one value of each class (Row::every_value); FuzzCliFull (label
// "full", scripts/test.sh --full) gives every option every value.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <set>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "support.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using dw::test::bin;
using dw::test::lines;
using dw::test::TempDir;

namespace {

// ----------------------------------------------------------------------------------------------
// The table
// ----------------------------------------------------------------------------------------------

// What a path option is to its tool.
enum class Role {
    in,      // a file or folder it reads
    out,     // a file it writes
    outdir,  // a folder it writes
    png,     // a PNG picture it writes
};

struct PathOption {
    // "--opt" (replaced, or appended when the base argv lacks it), or a positional placeholder
    // exactly as it appears in the base argv ("{mcap}", "{out}/recovered.mcap").
    std::string target;
    Role role;
    std::string ext;  // the extension hostile names get (".yaml"), so extension checks pass
    // "" means "not given" (the option is optional or has a default). Otherwise an empty path is
    // bad input and must be refused with 2.
    bool empty_means_default = false;
    std::string prefix = "";  // put before the path ("note=" for --attach NAME=PATH)
    std::string stem = "";    // put before hostile names ("cf50_": dw-import reads the vehicle from it)
};

struct Row {
    std::string name;  // test name
    std::string tool;
    std::string sub;  // subcommand whose --help lists the numeric options ("" = the tool's own help)
    // A minimal valid command line. Placeholders: {out} (the run's work folder, also its working
    // directory), {domain} (this process's private DDS domain), {flight} {mcap} {model} {loads}
    // {labfile} {ns_log} {ns_log2} {study} (fixtures, made once per test process).
    std::vector<std::string> argv;
    std::chrono::milliseconds bound;  // then SIGINT; batch rows finish well inside it
    // The row runs until stopped (a daemon, or a documented "until Ctrl-C" mode): its normal end
    // is a stop, so 0 after SIGINT is accepted besides 130. Batch work must say 130.
    bool until_stopped = false;
    // Also attack the tool's root options (--domain, --config). Only on rows that make no DDS
    // participant, so "--domain 0" puts no traffic on the default domain; the options are shared
    // (dw::dds::ProcessCli, dw::cli::configure), so one row per tool covers them.
    bool root_options = false;
    std::vector<std::string> skip;     // numeric options not to attack
    std::vector<PathOption> paths;     // path options to attack (listed by hand)
    std::vector<std::string> outputs;  // what a failed run must not leave (placeholders)
    // Every hostile number on every numeric option (FuzzCliFull, under --full). Otherwise each
    // option gets one value of each class — one that is no number and one number at an edge —
    // taken in turn from the lists, so that every value still meets some option of the row.
    bool every_value = false;
};

// gtest prints parameters in test listings and failures: the row's name, not its bytes.
void PrintTo(const Row& row, std::ostream* os) { *os << row.name; }

const PathOption kConfig{"--config", Role::in, ".yaml"};

std::vector<Row> table() {
    constexpr auto quick = std::chrono::milliseconds(20000);
    constexpr auto daemon = std::chrono::milliseconds(2500);
    return {
        // ---- dw-probe
        {"probe_list", "dw-probe", "list", {"list", "--domain", "{domain}"}, quick, false, true, {}, {kConfig}, {}},
        {"probe_pub",
         "dw-probe",
         "pub",
         {"pub", "--domain", "{domain}", "--count", "5", "--rate", "100", "--quiet"},
         std::chrono::milliseconds(5000),
         /*--linger -1: until stopped*/ true,
         false,
         {},
         {},
         {}},
        {"probe_echo",
         "dw-probe",
         "echo",
         {"echo", "--domain", "{domain}", "--quiet"},
         daemon,
         true,
         false,
         {},
         {{"--summary", Role::out, ".json", true}},
         {}},
        // ---- dw-viewer (a daemon: it serves until stopped)
        {"viewer", "dw-viewer", "", {"--domain", "{domain}", "--port", "0"}, daemon, true, false, {}, {}, {}},
        // ---- dw-lab
        {"lab_loopback",
         "dw-lab",
         "loopback",
         {"loopback", "--domain", "{domain}", "--count", "3", "--quiet", "--summary", "{out}/summary.json"},
         quick,
         false,
         false,
         {},
         {{"--summary", Role::out, ".json", true}},
         {"{out}/summary.json"}},
        {"lab_run",
         "dw-lab",
         "run",
         {"run", "--lab", "{labfile}", "--run-dir", "{out}/run", "--domain", "{domain}"},
         std::chrono::milliseconds(3000),
         true,
         false,
         {},
         {{"--lab", Role::in, ".yaml"}, {"--run-dir", Role::outdir, "", true}},
         {"{out}/run"}},
        // A whole simulated lab: stopped after 4 s, which also checks that a stop reaches every child.
        {"lab_demo",
         "dw-lab",
         "demo",
         {"demo", "--quick", "--out", "{out}/demo", "--domain", "{domain}"},
         std::chrono::milliseconds(4000),
         false,
         false,
         {},
         {{"--out", Role::outdir, "", true}},
         {"{out}/demo"}},
        // ---- dw-sim
        {"sim_fly",
         "dw-sim",
         "fly",
         {"fly", "--formation", "single", "--legs", "1", "--quiet", "--out", "{out}/flight"},
         quick,
         false,
         true,
         {},
         {{"--physics", Role::in, ".yaml", true}, {"--out", Role::outdir, ""}, kConfig},
         {"{out}/flight"}},
        // ---- dw-recorder
        {"recorder_record",
         "dw-recorder",
         "record",
         {"record", "--domain", "{domain}", "--quiet", "--duration", "1", "-o", "{out}/rec.mcap"},
         std::chrono::milliseconds(5000),
         /*--duration 0: until Ctrl-C*/ true,
         false,
         {},
         {{"-o", Role::out, ".mcap"}, {"--attach", Role::in, ".yaml", false, "note="}},
         {"{out}/rec.mcap"}},
        {"recorder_info",
         "dw-recorder",
         "info",
         {"info", "{mcap}"},
         quick,
         false,
         true,
         {},
         {{"{mcap}", Role::in, ".mcap"}, kConfig},
         {}},
        {"recorder_recover",
         "dw-recorder",
         "recover",
         {"recover", "{mcap}", "{out}/recovered.mcap"},
         quick,
         false,
         false,
         {},
         {{"{mcap}", Role::in, ".mcap"}, {"{out}/recovered.mcap", Role::out, ".mcap"}},
         {"{out}/recovered.mcap"}},
        {"recorder_export",
         "dw-recorder",
         "export",
         {"export", "{mcap}", "--flight", "{out}/flight", "--csv", "{out}/csv"},
         quick,
         false,
         false,
         {},
         {{"{mcap}", Role::in, ".mcap"}, {"--flight", Role::outdir, "", true}, {"--csv", Role::outdir, "", true}},
         {"{out}/flight", "{out}/csv"}},
        {"recorder_replay",
         "dw-recorder",
         "replay",
         {"replay", "{mcap}", "--domain", "{domain}", "--speed", "10"},
         quick,
         false,
         false,
         {},
         {{"{mcap}", Role::in, ".mcap"}},
         {}},
        // ---- dw-stand-agent
        {"stand_run",
         "dw-stand-agent",
         "run",
         {"run", "--sim", "--domain", "{domain}"},
         daemon,
         true,
         false,
         {},
         {{"--calibration", Role::in, ".yaml", true}, {"--physics", Role::in, ".yaml", true}},
         {}},
        {"stand_calibrate",
         "dw-stand-agent",
         "calibrate",
         {"calibrate", "--loads", "{loads}", "--out", "{out}/cal.yaml"},
         quick,
         false,
         true,
         {},
         {{"--loads", Role::in, ".csv"},
          {"--out", Role::out, ".yaml"},
          {"--calibration", Role::in, ".yaml", true},
          kConfig},
         {"{out}/cal.yaml"}},
        // ---- dw-mocap-bridge, dw-natnet-emulator (no subcommands: their options are the root's)
        {"mocap_bridge",
         "dw-mocap-bridge",
         "",
         {"--sim", "--domain", "{domain}"},
         daemon,
         true,
         false,
         {"--domain"},
         {kConfig},
         {}},
        {"natnet_emulator", "dw-natnet-emulator", "", {"--port", "0"}, daemon, true, false, {}, {kConfig}, {}},
        // ---- dw-px4-sim (issue 20)
        {"px4_sim",
         "dw-px4-sim",
         "",
         {"--vehicles", "v1", "--domain", "{domain}"},
         daemon,
         true,
         false,
         {"--domain"},
         {{"--px4", Role::in, ".yaml"}, kConfig},
         {}},
        // ---- dw-planner
        {"planner_plan",
         "dw-planner",
         "plan",
         {"plan", "--formation", "single", "--legs", "2", "--out", "{out}/plan.yaml"},
         quick,
         false,
         true,
         {},
         {{"--out", Role::out, ".yaml"}, {"--picture", Role::png, ".png", true}, kConfig},
         {"{out}/plan.yaml", "{out}/plan.png"}},
        // --wait-for '': no process to wait for; it then waits up to 30 s for the vehicle's pose (no
        // vehicle here): stopped after 3 s.
        {"planner_run",
         "dw-planner",
         "run",
         {"run", "--formation", "single", "--legs", "2", "--domain", "{domain}", "--wait-for", "", "--vehicles", "px4"},
         std::chrono::milliseconds(3000),
         false,
         false,
         {},
         {{"--px4", Role::in, ".yaml"}},
         {}},
        // ---- dw-predictor
        {"predictor_study",
         "dw-predictor",
         "study",
         {"study", "--out", "{out}/study", "--legs", "5", "--epochs", "1", "--no-generalisation", "--no-maps"},
         std::chrono::milliseconds(40000),
         false,
         false,
         {},
         {{"--out", Role::outdir, ""}, {"--physics", Role::in, ".yaml", true}},
         {"{out}/study"}},
        {"predictor_train",
         "dw-predictor",
         "train",
         {"train", "--kind", "learnt_linear", "--epochs", "1", "--data", "{flight}", "--out", "{out}/model.json"},
         quick,
         false,
         true,
         {},
         {{"--data", Role::in, ".mcap"}, {"--out", Role::out, ".json"}, kConfig},
         {"{out}/model.json"}},
        {"predictor_compare",
         "dw-predictor",
         "compare",
         {"compare", "--models", "{model}", "--data", "{flight}", "--out", "{out}/cmp"},
         quick,
         false,
         false,
         {},
         {{"--models", Role::in, ".json"}, {"--data", Role::in, ".mcap"}, {"--out", Role::outdir, ""}},
         {"{out}/cmp"}},
        {"predictor_real",
         "dw-predictor",
         "real",
         {"real", "--data", "{flight}", "--out", "{out}/real", "--epochs", "1"},
         std::chrono::milliseconds(40000),
         false,
         false,
         {},
         {{"--data", Role::in, ".mcap"}, {"--out", Role::outdir, ""}, {"--physics", Role::in, ".yaml", true}},
         {"{out}/real"}},
        {"predictor_regimes",
         "dw-predictor",
         "regimes",
         {"regimes", "--study", "{study}"},
         quick,
         false,
         false,
         {},
         {{"--study", Role::in, ""}},
         {}},
        {"predictor_map",
         "dw-predictor",
         "map",
         {"map", "--models", "{model}", "--formation", "single", "--out", "{out}/map.png"},
         quick,
         false,
         false,
         {},
         {{"--models", Role::in, ".json"},
          {"--data", Role::in, ".mcap"},
          {"--out", Role::png, ".png"},
          {"--line", Role::png, ".png", true}},
         {"{out}/map.png", "{out}/map_line.png"}},
        {"predictor_run",
         "dw-predictor",
         "run",
         {"run", "--model", "{model}", "--domain", "{domain}"},
         daemon,
         true,
         false,
         {},
         {{"--model", Role::in, ".json"}, {"--vehicles", Role::in, ".json", true}},
         {}},
        // ---- dw-explain
        {"explain",
         "dw-explain",
         "",
         {"--real", "{flight}", "--out", "{out}/explain", "--quiet"},
         quick,
         false,
         true,
         {},
         {{"--real", Role::in, ".mcap"}, {"--out", Role::outdir, ""}, {"--physics", Role::in, ".yaml", true}, kConfig},
         {"{out}/explain"}},
        {"explain_proof",
         "dw-explain",
         "proof",
         {"proof", "--out", "{out}/proof", "--null-seeds", "1", "--cases", "null", "--quiet"},
         std::chrono::milliseconds(40000),
         false,
         false,
         {},
         {{"--out", Role::outdir, ""}},
         {"{out}/proof"}},
        // ---- dw-import (its logs: the shared Neural-Swarm collection; the row is skipped without it)
        {"import_neural_swarm",
         "dw-import",
         "neural-swarm",
         {"neural-swarm", "{ns_log}", "{ns_log2}", "--out", "{out}/flight"},
         quick,
         false,
         true,
         {},
         {{"{ns_log}", Role::in, ".csv", false, "", "cf50_"}, {"--out", Role::outdir, ""}, kConfig},
         {"{out}/flight"}},
    };
}

// The hostile values. Numbers: every numeric option. Paths: every listed path option.
const std::vector<std::string> kNumbers{"nan", "inf", "-inf", "-1", "0", "1e308", "1e-300", "", "x"};
// Never a number: whatever the option, the answer is 2.
const std::set<std::string> kNeverNumbers{"nan", "inf", "-inf", "", "x"};
enum class HostilePath { directory, missing, empty_file, unreadable, empty_string, not_png };
const char* name_of(HostilePath h) {
    switch (h) {
        case HostilePath::directory: return "directory";
        case HostilePath::missing: return "missing";
        case HostilePath::empty_file: return "empty_file";
        case HostilePath::unreadable: return "unreadable";
        case HostilePath::empty_string: return "empty_string";
        case HostilePath::not_png: return "not_png";
    }
    return "?";
}

// ----------------------------------------------------------------------------------------------
// Fixtures: made once per test process (each row is its own process under CTest), and only
// those the row's base command line names.
// ----------------------------------------------------------------------------------------------

std::string slurp(const std::string& path) {
    try {
        return dw::read_file(path);
    } catch (...) {
        return "";
    }
}

// Runs a helper command to completion; returns its status, stderr in `err`.
int run_helper(const std::vector<std::string>& argv, const std::string& dir, std::string* err = nullptr,
               std::chrono::milliseconds limit = 120s) {
    static int n = 0;
    const std::string tag = dir + "/helper" + std::to_string(n++);
    dw::Subprocess p({argv, tag + ".out", tag + ".err", {}});
    const auto st = p.wait_for(limit);
    const int status = st ? *st : p.stop();
    if (err != nullptr) *err = slurp(tag + ".out") + slurp(tag + ".err");
    return status;
}

class Fixtures {
public:
    explicit Fixtures(std::string dir) : dir_(std::move(dir)) {}

    // Every fixture a row's command line may name as {name}: the makers' list below.
    static std::vector<std::string> names() {
        std::vector<std::string> out;
        for (const auto& m : kMakers) out.emplace_back(m.name);
        return out;
    }

    // The fixture's path; empty and *problem set when it could not be made.
    std::string get(const std::string& name, std::string* problem) {
        if (auto it = made_.find(name); it != made_.end()) return it->second;
        const auto m = std::find_if(kMakers.begin(), kMakers.end(), [&](const Maker& k) { return name == k.name; });
        if (m == kMakers.end()) {
            *problem = "unknown fixture {" + name + "}";
            return "";
        }
        const std::string path = (this->*(m->make))(name, problem);
        if (!path.empty()) made_[name] = path;
        return path;
    }

private:
    using Make = std::string (Fixtures::*)(const std::string& name, std::string* problem);
    struct Maker {
        const char* name;
        Make make;
    };
    static const std::array<Maker, 8> kMakers;

    // The path when the helper succeeded; else "" and *problem = what: its output.
    std::string made_by(const std::vector<std::string>& argv, const std::string& path, const char* what,
                        std::string* problem) {
        std::string err;
        if (run_helper(argv, dir_, &err) == 0) return path;
        *problem = std::string(what) + ": " + err;
        return "";
    }
    std::string flight(const std::string&, std::string* problem) {
        const std::string path = dir_ + "/flight";
        return made_by({bin("dw-sim"), "fly", "--formation", "single", "--legs", "5", "--quiet", "--out", path}, path,
                       "dw-sim fly", problem);
    }
    std::string model(const std::string&, std::string* problem) {
        const std::string flight = get("flight", problem);
        if (flight.empty()) return "";
        const std::string path = dir_ + "/model.json";
        return made_by(
            {bin("dw-predictor"), "train", "--kind", "learnt_linear", "--epochs", "1", "--data", flight, "--out", path},
            path, "dw-predictor train", problem);
    }
    std::string study(const std::string&, std::string* problem) {
        const std::string path =
            dir_ + "/study";  // the smallest study: its flights and models are what `regimes` reads
        return made_by({bin("dw-predictor"), "study", "--out", path, "--legs", "15", "--epochs", "1",
                        "--no-generalisation", "--no-maps"},
                       path, "dw-predictor study", problem);
    }
    // A short recording of dw-probe's deterministic samples on this process's own domain. If the
    // publisher finds no reader in time the recording still holds the heartbeats: a valid, smaller
    // file, good enough for info/recover/export/replay.
    std::string mcap(const std::string&, std::string* problem) {
        const std::string path = dir_ + "/recording.mcap", domain = std::to_string(dw::test::test_domain());
        dw::Subprocess rec({{bin("dw-recorder"), "record", "--domain", domain, "--duration", "3", "--quiet",
                             "--no-command-control", "-o", path},
                            dir_ + "/rec.out",
                            dir_ + "/rec.err",
                            {}});
        std::this_thread::sleep_for(300ms);
        run_helper({bin("dw-probe"), "pub", "--domain", domain, "--count", "50", "--rate", "100", "--wait-readers", "1",
                    "--wait-timeout", "5", "--quiet"},
                   dir_);
        const auto st = rec.wait_for(30s);
        if (st && *st == 0 && fs::exists(path)) return path;
        *problem = "dw-recorder record: " + slurp(dir_ + "/rec.err");
        return "";
    }
    std::string loads(const std::string&, std::string*) {
        const std::string path = dir_ + "/loads.csv";
        std::ofstream(path) << dw::test::known_loads_csv();
        return path;
    }
    // Two vehicles of one Neural-Swarm trial, read in place (as tests/test_import.cpp).
    std::string ns_log(const std::string& name, std::string* problem) {
        const std::string data = std::string(DW_SOURCE_DIR) +
                                 "/../shared/data/neural-swarm/data/training/datacollection21_06_16_2020/swap_ss/";
        const std::string path = data + (name == "ns_log" ? "cf50_01.csv" : "cf51_01.csv");
        if (fs::exists(path)) return path;
        *problem = "skip: the shared Neural-Swarm logs are not at " + data;
        return "";
    }
    // One process that runs until stopped: dw-lab run then runs until stopped too.
    std::string labfile(const std::string&, std::string*) {
        const std::string path = dir_ + "/lab.yaml";
        std::ofstream(path)
            << "format: downwash-lab/1\nprocesses:\n  - name: echo\n    run: [dw-probe, echo, --quiet]\n";
        return path;
    }

    std::string dir_;
    std::map<std::string, std::string> made_;
};

const std::array<Fixtures::Maker, 8> Fixtures::kMakers{{{"flight", &Fixtures::flight},
                                                        {"mcap", &Fixtures::mcap},
                                                        {"model", &Fixtures::model},
                                                        {"loads", &Fixtures::loads},
                                                        {"labfile", &Fixtures::labfile},
                                                        {"ns_log", &Fixtures::ns_log},
                                                        {"ns_log2", &Fixtures::ns_log},
                                                        {"study", &Fixtures::study}}};

// ----------------------------------------------------------------------------------------------
// One run
// ----------------------------------------------------------------------------------------------

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
        s.replace(at, from.size(), to);
    return s;
}

// Replaces the value of `target` in argv (an option: the word after it, appended when absent; a
// positional placeholder: that word).
std::vector<std::string> with_value(std::vector<std::string> argv, const std::string& target,
                                    const std::string& value) {
    const auto it = std::find(argv.begin(), argv.end(), target);
    if (target.rfind('-', 0) != 0) {
        if (it != argv.end()) *it = value;
        return argv;
    }
    if (it != argv.end() && it + 1 != argv.end()) {
        *(it + 1) = value;
    } else {
        argv.push_back(target);
        argv.push_back(value);
    }
    return argv;
}

// The numeric options a --help text lists: those carrying a range ("--speed FLOAT:[0.05, 3] m/s",
// "--domain ID:[0, 232]") and any FLOAT/INT/UINT one (dw::cli::parse refuses those without a range,
// but the harness should not rely on it).
std::vector<std::string> numeric_options(const std::string& help) {
    static const std::regex re(R"(^\s+(?:-\w,)?(--[a-z][a-z0-9-]*)\s+(?:(?:FLOAT|INT|UINT)\b|[A-Z]+:\[))");
    std::vector<std::string> out;
    for (const auto& line : lines(help)) {
        std::smatch m;
        if (std::regex_search(line, m, re) && std::find(out.begin(), out.end(), m[1].str()) == out.end()) {
            out.push_back(m[1].str());
        }
    }
    return out;
}

// A NaN or inf token in text ("nan", "-inf", ".inf", "NaN", "inf," ...): never in an output file.
std::optional<std::string> nan_line(const std::string& text) {
    static const std::regex re(R"((^|[,:\s\[="'(])(-?\.?nan|-?\.?inf)([,\s\]"')]|$))", std::regex::icase);
    std::string lower(text.size(), ' ');
    std::transform(text.begin(), text.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    for (const char* word : {"nan", "inf"}) {
        for (std::size_t at = lower.find(word); at != std::string::npos; at = lower.find(word, at + 1)) {
            const std::size_t b = lower.rfind('\n', at), e = lower.find('\n', at);
            const std::size_t start = b == std::string::npos ? 0 : b + 1;
            const std::string line = text.substr(start, e == std::string::npos ? std::string::npos : e - start);
            if (std::regex_search(line, re)) return line.substr(0, 160);
            if (e == std::string::npos) break;
            at = e;
        }
    }
    return std::nullopt;
}

// What a path is, to compare before and after a failed run.
std::string state_of(const std::string& path) {
    std::error_code ec;
    if (path.empty() || !fs::exists(fs::symlink_status(path, ec))) return "absent";
    if (fs::is_directory(path, ec)) {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(path, ec)) names.push_back(e.path().filename().string());
        std::sort(names.begin(), names.end());
        std::string s = "folder {";
        for (const auto& n : names) s += " " + n;
        return s + " }";
    }
    return "file of " + std::to_string(fs::file_size(path, ec)) + " bytes";
}

struct Case {
    std::string label;              // "--speed nan", "--out=directory"
    std::vector<std::string> argv;  // with placeholders
    bool never_a_number = false;
    bool base = false;                 // the unchanged base command: it must succeed
    const PathOption* path = nullptr;  // the attacked path option, if any
    HostilePath hostile{};
};

class Attempt {
public:
    Attempt() {
        std::error_code ec;
        fs::create_directories(work(), ec);
        fs::create_directories(hostile_dir(), ec);
    }
    std::string root() const { return root_.file(""); }
    std::string work() const { return root_.file("work"); }
    std::string hostile_dir() const { return root_.file("hostile"); }
    std::string out_file() const { return root_.file("stdout"); }
    std::string err_file() const { return root_.file("stderr"); }

    // Makes the hostile path for `o` inside this run's folder; returns it and, in *watch, the path
    // whose state must not change when the run fails ("" = nothing to watch).
    std::string make(HostilePath h, const PathOption& o, std::string* watch) {
        const std::string d = hostile_dir();
        std::string p;
        switch (h) {
            case HostilePath::directory:
                p = d + "/" + o.stem + "dir" + o.ext;
                fs::create_directories(p);
                break;
            case HostilePath::missing:
                // An input that is not there; an output in folders that are not there yet.
                p = o.role == Role::in ? d + "/" + o.stem + "missing" + o.ext
                                       : d + "/no/such/folder/" + o.stem + "out" + o.ext;
                break;
            case HostilePath::empty_file:
                p = d + "/" + o.stem + "empty" + o.ext;
                std::ofstream{p};
                break;
            case HostilePath::unreadable:
                p = d + "/" + o.stem + "unreadable" + o.ext;
                std::ofstream{p} << "format: unreadable\n";
                ::chmod(p.c_str(), 0);
                break;
            case HostilePath::empty_string: break;
            case HostilePath::not_png: p = d + "/picture.txt"; break;
        }
        *watch = o.role == Role::in || p.empty() ? "" : (h == HostilePath::missing ? d + "/no" : p);
        return p;
    }

    struct Result {
        int status = -1;
        bool stopped = false;  // SIGINT was sent
        bool hung = false;     // ... and it did not end within 10 s
        std::string err;
    };

    Result start(const std::vector<std::string>& argv, std::chrono::milliseconds bound) {
        // Tools write default outputs (plan.yaml, recording.mcap, runs/...) in the working
        // directory: run each in its own folder. One run at a time per process, so chdir is safe.
        struct Cwd {
            fs::path saved = fs::current_path();
            explicit Cwd(const std::string& to) { fs::current_path(to); }
            ~Cwd() { fs::current_path(saved); }
        };
        Result r;
        {
            std::optional<dw::Subprocess> started;
            {
                Cwd cwd(work());
                started.emplace(dw::SpawnOptions{argv, out_file(), err_file(), {}});
            }
            dw::Subprocess& p = *started;
            auto st = p.wait_for(bound);
            if (!st) {
                r.stopped = true;
                p.signal(SIGINT);
                st = p.wait_for(10s);
                if (!st) {
                    r.hung = true;
                    st = p.stop(3000ms);  // SIGTERM, then SIGKILL
                }
            }
            r.status = st.value_or(-1);
        }
        r.err = slurp(err_file());
        return r;
    }

    // Problems with the files the run left: NaN/inf tokens, temporaries.
    void scan(std::vector<std::string>& problems) const {
        std::error_code ec;
        for (auto it = fs::recursive_directory_iterator(root(), fs::directory_options::skip_permission_denied, ec);
             it != fs::recursive_directory_iterator(); it.increment(ec)) {
            if (ec) break;
            const fs::path p = it->path();
            const std::string name = p.filename().string();
            if (name.find(".tmp-") != std::string::npos)
                problems.push_back("temporary file left: " + shorten(p.string()));
            if (!it->is_regular_file(ec) || p == fs::path(out_file()) || p == fs::path(err_file())) continue;
            const std::string ext = p.extension().string();
            if (ext == ".png" || ext == ".mcap") continue;  // binary
            const std::string text = slurp(p.string());
            if (text.find('\0') != std::string::npos) continue;  // binary
            if (const auto line = nan_line(text))
                problems.push_back("NaN/inf in " + shorten(p.string()) + ": " + *line);
        }
    }

    std::string shorten(const std::string& s) const { return replace_all(s, root(), "$T/"); }

private:
    TempDir root_;
};

std::string quoted(const std::vector<std::string>& argv) {
    std::string s;
    for (const auto& a : argv) {
        if (!s.empty()) s += ' ';
        s += a.empty() || a.find_first_of(" \t'\"") != std::string::npos ? "'" + a + "'" : a;
    }
    return s;
}

// ----------------------------------------------------------------------------------------------
// The test: one per row
// ----------------------------------------------------------------------------------------------

class Tool : public ::testing::TestWithParam<Row> {
protected:
    static void SetUpTestSuite() {
        fixture_dir_ = std::make_unique<TempDir>();
        fixtures_ = std::make_unique<Fixtures>(fixture_dir_->file("fixtures"));
        fs::create_directories(fixture_dir_->file("fixtures"));
    }
    static void TearDownTestSuite() {
        fixtures_.reset();
        fixture_dir_.reset();
    }
    static std::unique_ptr<TempDir> fixture_dir_;
    static std::unique_ptr<Fixtures> fixtures_;

public:
    static std::string fixture_dir() { return fixture_dir_ ? fixture_dir_->file("") : std::string("\x01"); }
};
std::unique_ptr<TempDir> Tool::fixture_dir_;
std::unique_ptr<Fixtures> Tool::fixtures_;

std::string shorten_fixtures(const std::string& s) { return replace_all(s, Tool::fixture_dir(), "$F/"); }

std::string help_of(const std::string& tool, const std::string& sub) {
    TempDir d;
    std::vector<std::string> argv{bin(tool)};
    if (!sub.empty()) argv.push_back(sub);
    argv.push_back("--help");
    dw::Subprocess p({argv, d.file("help"), d.file("help.err"), {}});
    const auto st = p.wait_for(10s);
    if (!st) p.stop();
    return slurp(d.file("help"));
}

// The hostile numbers the row's `turn`-th numeric option gets (Row::every_value).
std::vector<std::string> values_for(const Row& row, std::size_t turn) {
    if (row.every_value) return kNumbers;
    std::vector<std::string> never, edge;
    for (const auto& v : kNumbers) (kNeverNumbers.count(v) ? never : edge).push_back(v);
    turn += row.name.size();  // rows start at different places in the lists
    return {never[turn % never.size()], edge[turn % edge.size()]};
}

std::vector<Case> cases_of(const Row& row) {
    std::vector<std::string> numeric = numeric_options(help_of(row.tool, row.sub));
    if (row.root_options && !row.sub.empty()) {
        for (const auto& o : numeric_options(help_of(row.tool, ""))) {
            if (std::find(numeric.begin(), numeric.end(), o) == numeric.end()) numeric.push_back(o);
        }
    }
    std::vector<Case> cases;
    std::size_t turn = 0;  // the option's place in the row, for the values it gets in turn
    for (const auto& o : numeric) {
        if (std::find(row.skip.begin(), row.skip.end(), o) != row.skip.end()) continue;
        for (const auto& v : values_for(row, turn++)) {
            cases.push_back({o + " " + (v.empty() ? "''" : v), with_value(row.argv, o, v), kNeverNumbers.count(v) > 0});
        }
    }
    for (const auto& p : row.paths) {
        for (HostilePath h : {HostilePath::directory, HostilePath::missing, HostilePath::empty_file,
                              HostilePath::unreadable, HostilePath::empty_string, HostilePath::not_png}) {
            if (h == HostilePath::not_png && p.role != Role::png) continue;
            // As root every file is readable: the unreadable value would test nothing (CI runs as root).
            if (h == HostilePath::unreadable && ::geteuid() == 0) continue;
            Case c;
            c.label = p.target + "=" + name_of(h);
            c.argv = row.argv;
            c.path = &p;
            c.hostile = h;
            cases.push_back(c);
        }
    }
    return cases;
}

// The fixtures a row's base command names, made on first use.
std::map<std::string, std::string> fixtures_for(const Row& row, Fixtures& fixtures, std::string* problem) {
    std::map<std::string, std::string> out;
    for (const auto& a : row.argv) {
        for (const auto& name : Fixtures::names()) {
            if (a.find(std::string("{") + name + "}") == std::string::npos || out.count(name)) continue;
            const std::string path = fixtures.get(name, problem);
            if (path.empty()) return {};
            out[name] = path;
        }
    }
    return out;
}

// Runs one case of a row (bound: when to send SIGINT) and reports every broken rule as one failure.
void attempt(const Row& row, const Case& c, const std::map<std::string, std::string>& fixture,
             std::chrono::milliseconds bound) {
    Attempt run;
    std::vector<std::string> argv = c.argv;
    std::string watch, watch_before;
    if (c.path != nullptr) {
        const std::string value = run.make(c.hostile, *c.path, &watch);
        argv = with_value(argv, c.path->target, c.path->prefix + value);
        watch_before = state_of(watch);
    }
    auto expand = [&](std::string a) {
        a = replace_all(a, "{out}", run.work());
        a = replace_all(a, "{domain}", std::to_string(dw::test::test_domain()));
        for (const auto& [name, path] : fixture) a = replace_all(a, "{" + name + "}", path);
        return a;
    };
    std::vector<std::string> full{bin(row.tool)};
    for (const auto& a : argv) full.push_back(expand(a));

    const auto r = run.start(full, bound);
    // 0 after SIGINT: the normal end of a row that runs until stopped; and for the early stop of a
    // base command, work that finished as the signal landed (its outputs are complete: written
    // atomically). A hostile run reaches its bound only in long work, where it must say 130.
    const bool zero_after_stop_ok = row.until_stopped || c.base;
    std::vector<std::string> problems;
    std::vector<std::string> err_lines;
    for (const auto& s : lines(r.err)) {
        if (s.find_first_not_of(" \t\r") != std::string::npos) err_lines.push_back(s);
    }

    if (r.hung) {
        problems.push_back("still running 10 s after SIGINT (killed)");
    } else if (r.status != 0 && r.status != 1 && r.status != 2 && r.status != 130) {
        problems.push_back("exit status " + std::to_string(r.status) + " (expected 0, 1, 2 or 130)");
    } else if (r.stopped && r.status != 130 && !(zero_after_stop_ok && r.status == 0)) {
        problems.push_back("status " + std::to_string(r.status) + " after SIGINT (expected 130" +
                           (zero_after_stop_ok ? " or 0)" : ")"));
    }
    if (c.never_a_number && r.status != 2) problems.push_back("a value that is no number was not refused with 2");
    if (c.path != nullptr && c.hostile == HostilePath::empty_string && !c.path->empty_means_default && r.status != 2) {
        problems.push_back("an empty path for an option without a default was not refused with 2");
    }
    if (c.base && !r.stopped && r.status != 0) problems.push_back("the valid base command failed");
    // Bad input (2) is refused before any work: one line. A runtime failure (1) may follow the
    // progress lines of work done so far, but says what failed in exactly one error line.
    std::vector<std::string> error_lines;
    for (const auto& l : err_lines)
        if (l.find(": error: ") != std::string::npos) error_lines.push_back(l);
    const auto& counted = r.status == 2 ? err_lines : error_lines;
    if (r.status == 1 || r.status == 2) {
        if (counted.size() != 1) {
            problems.push_back(std::to_string(counted.size()) + (r.status == 2 ? " lines" : " error lines") +
                               " on stderr (expected one)");
        } else if (counted[0].rfind(row.tool + ": error: ", 0) != 0) {
            problems.push_back("the stderr line is not '" + row.tool + ": error: ...'");
        }
    }
    run.scan(problems);  // no NaN/inf in any output, no temporary left (whatever the status)
    // Stopped (130): what was written is whole (atomic writes), so only failures must leave nothing.
    if (r.status != 0 && r.status != 130) {
        const bool output_attacked = c.path != nullptr && c.path->role != Role::in;
        for (const auto& o : row.outputs) {
            // When an output option is attacked, derived names (plan.png beside --out) move with it:
            // then only outputs the command line still names are checked (the attacked one is
            // watched instead).
            if (output_attacked && std::find(argv.begin(), argv.end(), o) == argv.end()) continue;
            const std::string path = expand(o);
            if (fs::exists(path)) problems.push_back("output left after failure: " + run.shorten(path));
        }
        if (!watch.empty() && state_of(watch) != watch_before) {
            problems.push_back("attacked output " + run.shorten(watch) + " changed by a failed run: " + watch_before +
                               " -> " + state_of(watch));
        }
    }
    if (!problems.empty()) {
        std::vector<std::string> shown = full;
        shown[0] = row.tool;
        std::string msg = "[" + c.label + "] " + shorten_fixtures(run.shorten(quoted(shown))) + "\n  status " +
                          std::to_string(r.status) + (r.stopped ? " (after SIGINT)" : "");
        for (const auto& p : problems) msg += "\n  - " + p;
        std::string err = run.shorten(r.err);
        if (err.size() > 600) err = "..." + err.substr(err.size() - 600);
        msg += "\n  stderr: " + replace_all(err, "\n", "\n          ");
        ADD_FAILURE() << msg;
    }
}

TEST_P(Tool, HostileValues) {
    const Row& row = GetParam();
    std::string problem;
    const auto fixture = fixtures_for(row, *fixtures_, &problem);
    if (problem.rfind("skip: ", 0) == 0) GTEST_SKIP() << problem.substr(6);
    ASSERT_TRUE(problem.empty()) << "fixture: " << problem;
    const auto cases = cases_of(row);
    ASSERT_FALSE(cases.empty()) << row.tool << " " << row.sub
                                << ": no numeric option found in --help and no path option listed";
    for (const auto& c : cases) attempt(row, c, fixture, row.bound);
}

// The valid base command, interrupted early (batch rows after 1 s, rows that run until stopped
// after their bound): it must end within 10 s with 130, or 0 when its work had already finished
// (fast rows finish before the signal; a slow one may finish as it lands), and on 130 leave none of
// its outputs and no temporary file.
TEST_P(Tool, StopsWhenAsked) {
    const Row& row = GetParam();
    if (row.every_value) GTEST_SKIP() << "the base command has no hostile values: FuzzCli/Tool.StopsWhenAsked runs it";
    std::string problem;
    const auto fixture = fixtures_for(row, *fixtures_, &problem);
    if (problem.rfind("skip: ", 0) == 0) GTEST_SKIP() << problem.substr(6);
    ASSERT_TRUE(problem.empty()) << "fixture: " << problem;
    Case c;
    c.label = "base, SIGINT";
    c.argv = row.argv;
    c.base = true;
    attempt(row, c, fixture, row.until_stopped ? row.bound : std::chrono::milliseconds(1000));
}

std::vector<Row> every_value(std::vector<Row> rows) {
    for (auto& r : rows) r.every_value = true;
    return rows;
}

const auto kRowName = [](const ::testing::TestParamInfo<Row>& info) { return info.param.name; };
INSTANTIATE_TEST_SUITE_P(FuzzCli, Tool, ::testing::ValuesIn(table()), kRowName);
INSTANTIATE_TEST_SUITE_P(FuzzCliFull, Tool, ::testing::ValuesIn(every_value(table())), kRowName);

}  // namespace
