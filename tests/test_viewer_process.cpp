// The viewer of a running simulated lab (issue 72): an independent Foxglove client decodes every
// channel, a stalled client costs the live ones nothing, and the page in a real browser shows the
// lab live. Each test flies a short lab (dw-lab run) with dw-viewer beside it on the same domain.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/files.hpp"
#include "core/subprocess.hpp"
#include "dds/topics.hpp"
#include "support.hpp"

using namespace std::chrono_literals;
using dw::test::bin;
using json = nlohmann::json;

namespace {

// The simulated lab: the stand, mocap and two vehicles simulated, the physics as the predictor,
// a single-neighbour experiment long enough for every test (stopped by the test).
constexpr const char* kLab = R"(format: downwash-lab/1
hosts:
  local: {}
processes:
  - name: recorder
    run: [dw-recorder, record, --out, "{run_dir}/exp.mcap", --quiet, --no-fsync]
  - name: stand_agent
    run: [dw-stand-agent, run, --sim]
  - name: mocap_bridge
    run: [dw-mocap-bridge, --sim, --sim-vehicles, v1]
  - name: predictor
    run: [dw-predictor, run, --model, PHYSICS]
  - name: planner
    run: [dw-planner, run, --formation, single, --legs, "40", --altitudes, "0.5", --speed, "1.0"]
    experiment: true
)";

constexpr std::chrono::milliseconds kLabStopGrace{60000};

std::string js(const std::string& script) { return std::string(DW_SOURCE_DIR) + "/tests/js/" + script; }

struct LiveLab {
    dw::test::TempDir dir;
    std::string domain = std::to_string(dw::test::test_domain());
    std::string ns = "view" + std::to_string(::getpid());
    std::optional<dw::Subprocess> lab, viewer;
    std::string url;  // http://127.0.0.1:<port>/

    LiveLab() {
        std::string text = kLab;
        text.replace(text.find("PHYSICS"), 7, std::string(DW_SOURCE_DIR) + "/config/physics.example.yaml");
        std::ofstream(dir.file("lab.yaml")) << text;
        viewer.emplace(dw::SpawnOptions{{bin("dw-viewer"), "--port", "0", "--domain", domain, "--namespace", ns},
                                        dir.file("viewer.out"),
                                        dir.file("viewer.err"),
                                        {}});
        lab.emplace(dw::SpawnOptions{{bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run"),
                                      "--domain", domain, "--namespace", ns},
                                     dir.file("lab.out"),
                                     dir.file("lab.err"),
                                     {}});
        for (int i = 0; i < 1000 && url.empty(); ++i) {
            const auto out = dw::read_file(dir.file("viewer.out"));
            if (const auto at = out.find("viewer at ");
                at != std::string::npos && out.find('\n', at) != std::string::npos)
                url = out.substr(at + 10, out.find('\n', at) - at - 10);
            else std::this_thread::sleep_for(10ms);
        }
    }
    // The lab stopped as a person would (SIGTERM: dw-lab stops its processes first; a SIGKILL would
    // leave them running), then the viewer.
    ~LiveLab() {
        if (lab) lab->stop(kLabStopGrace);
        if (viewer) viewer->stop();
    }
    std::string ws() const { return "ws://" + url.substr(7); }
    // Until the experiment flies a leg (the state says so), at most `limit`.
    bool flying(std::chrono::seconds limit) const {
        for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;) {
            if (dw::read_file(dir.file("lab.err")).find("FLYING") != std::string::npos) return true;
            std::this_thread::sleep_for(100ms);
        }
        return false;
    }
    std::string logs() const {
        return "viewer:\n" + dw::read_file(dir.file("viewer.err")) + "\nlab:\n" + dw::read_file(dir.file("lab.err"));
    }
    // The viewer's peak resident memory so far [kB] (VmHWM).
    long peak_kb() const {
        std::ifstream f("/proc/" + std::to_string(viewer->pid()) + "/status");
        for (std::string line; std::getline(f, line);)
            if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
        return -1;
    }
};

json run_json(const std::vector<std::string>& argv, const dw::test::TempDir& dir) {
    const auto r = dw::test::run(argv, dir, 120000ms);
    EXPECT_EQ(r.status, 0) << r.err;
    const auto lines = dw::test::lines(r.out);
    return lines.empty() ? json() : json::parse(lines.back(), nullptr, false);
}

}  // namespace

TEST(ViewerProcess, AnIndependentFoxgloveClientDecodesEveryChannelOfARunningLab) {
    LiveLab lab;
    ASSERT_FALSE(lab.url.empty()) << lab.logs();
    ASSERT_TRUE(lab.flying(120s)) << lab.logs();
    const json r = run_json({"node", js("check_foxglove.mjs"), lab.ws(), "--seconds", "4"}, lab.dir);
    ASSERT_TRUE(r.is_object()) << lab.logs();
    const auto& c = r["clients"][0];
    EXPECT_EQ(c["subprotocol"], "foxglove.websocket.v1");
    EXPECT_EQ(c["channels"], dw::dds::topics::kTopicCount);
    EXPECT_TRUE(c["errors"].empty()) << c["errors"].dump();
    for (const auto& [topic, t] : c["topics"].items()) EXPECT_EQ(t["bad"], 0) << topic;
    // What a running lab says on its topics, all decoded (the state topics' newest at once, latched).
    for (const char* suffix : {"stand/wrench", "stand/cells", "mocap/frame", "vehicles/state", "vehicles/setpoint",
                               "predictor/wrench", "experiment/plan", "experiment/state", "processes/status"}) {
        const std::string topic = "rt/" + lab.ns + "/" + suffix;
        ASSERT_TRUE(c["topics"].contains(topic)) << topic;
        EXPECT_GT(c["topics"][topic]["messages"].get<int>(), 0) << topic;
    }
}

// One client connected and never reading, three live ones: the live ones keep the stand's rate
// (each gets every wrench sample the others get), the stalled one loses its oldest sensor frames
// (the viewer says how many when it stops) and the viewer's memory stays bounded.
TEST(ViewerProcess, AStalledClientLosesOnlyItsOwnOldestSamplesAndTheViewerStaysBounded) {
    LiveLab lab;
    ASSERT_FALSE(lab.url.empty()) << lab.logs();
    ASSERT_TRUE(lab.flying(120s)) << lab.logs();
    constexpr double kSeconds = 8, kStandHz = 80;
    const json r = run_json(
        {"node", js("check_foxglove.mjs"), lab.ws(), "--seconds", "8", "--live", "3", "--stalled", "1"}, lab.dir);
    ASSERT_TRUE(r.is_object()) << lab.logs();
    const std::string wrench = "rt/" + lab.ns + "/stand/wrench";
    std::vector<int> counts;
    for (const auto& c : r["clients"]) {
        EXPECT_TRUE(c["errors"].empty()) << c["errors"].dump();
        counts.push_back(c["topics"][wrench]["messages"].get<int>());
    }
    ASSERT_EQ(counts.size(), 3u);
    const auto [lo, hi] = std::minmax_element(counts.begin(), counts.end());
    EXPECT_GE(*lo, 0.95 * *hi) << "a live client fell behind the others";
    EXPECT_GE(*lo, 0.8 * kStandHz * kSeconds) << "a live client lost the stand's rate";
    // Bounded: four clients' outboxes (kMaxQueuedBytes each) and the readers, well under this.
    constexpr long kViewerPeakKb = 200 * 1024;
    EXPECT_LT(lab.peak_kb(), kViewerPeakKb);
    lab.viewer->signal(SIGINT);
    ASSERT_EQ(lab.viewer->wait_for(20000ms), std::optional<int>(0)) << lab.logs();
    const auto err = dw::read_file(lab.dir.file("viewer.err"));
    const auto end = err.rfind(" dropped for slow clients");
    ASSERT_NE(end, std::string::npos) << err;
    const auto start = err.rfind(", ", end) + 2;
    EXPECT_GT(std::stol(err.substr(start, end - start)), 0) << "the stalled client lost nothing? " << err;
}

// The page in Debian's chromium, headless (puppeteer-core): it shows live values that change —
// the wrench, a vehicle moving, the experiment's progress — and its screenshot is saved
// (DW_VIEWER_SCREENSHOT names where; the README's picture is one).
TEST(ViewerProcess, ThePageInARealBrowserShowsTheLabLive) {
    const char* chromium = std::getenv("DW_CHROMIUM");
    if (!std::filesystem::exists(chromium ? chromium : "/usr/bin/chromium"))
        GTEST_SKIP() << "no /usr/bin/chromium (scripts/test.sh installs Debian's chromium)";
    LiveLab lab;
    ASSERT_FALSE(lab.url.empty()) << lab.logs();
    ASSERT_TRUE(lab.flying(120s)) << lab.logs();
    const char* keep = std::getenv("DW_VIEWER_SCREENSHOT");
    const std::string shot = keep ? keep : lab.dir.file("viewer.png");
    const json r = run_json({"node", js("check_viewer_page.mjs"), lab.url, shot, "--seconds", "3"}, lab.dir);
    ASSERT_TRUE(r.is_object()) << lab.logs();
    const auto &a = r["first"], &b = r["second"];
    EXPECT_TRUE(r["errors"].empty()) << r["errors"].dump();
    EXPECT_TRUE(a["connected"].get<bool>() && b["connected"].get<bool>());
    EXPECT_NE(a["f_d"], b["f_d"]) << "the wrench did not change";
    EXPECT_NE(a["f_d"], "–");
    EXPECT_NE(a["vehicles"], b["vehicles"]) << "no vehicle moved";
    EXPECT_NE(a["progress"], b["progress"]) << "the experiment's progress did not change";
    EXPECT_EQ(b["phase"], "FLYING");
    EXPECT_GE(b["processes"].get<int>(), 4) << "each process's status";
    EXPECT_TRUE(std::filesystem::exists(shot));
}
