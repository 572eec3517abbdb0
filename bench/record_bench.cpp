// dw-bench-record: how fast the recorder records through DDS without losing a sample, beside how
// fast raw Fast DDS delivers on loopback, measured in the same run. A dw-probe process publishes
// stand/wrench (best effort, as the stand does) at a swept rate; in this process a raw Fast DDS
// reader (counting only) and the recorder (writing MCAP, zstd) both subscribe to it.
//   build/bin/dw-bench-record [--rates 2000,5000,...] [--seconds 2]
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <thread>

#include "bench/raw_dds.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"
#include "dds/process_cli.hpp"
#include "recorder/recorder.hpp"

namespace fdds = eprosima::fastdds::dds;

namespace {

class RawCounter : public fdds::DataReaderListener {
public:
    explicit RawCounter(const dw::dds::DdsConfig& cfg) : participant_(cfg, "raw-counter") {
        auto qos = dw::dds::reader_qos(dw::dds::QosProfile::sensor);
        qos.history().depth = 1000;  // a fair reader: it keeps up, so losses are the transport's
        reader_ = participant_.subscriber()->create_datareader(participant_.topic("rt/" + cfg.ns + "/stand/wrench"),
                                                               qos, this);
    }
    ~RawCounter() override { reader_->set_listener(nullptr); }
    void on_data_available(fdds::DataReader* r) override {
        fdds::SampleInfo info;
        while (r->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
            if (info.valid_data) ++count;
        }
    }
    std::atomic<std::uint64_t> count{0};

private:
    dw::bench::RawParticipant participant_;
    fdds::DataReader* reader_ = nullptr;
    dw::msg::WrenchStamped sample_;
};

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-record", [&] {
        dw::Shutdown::install();
        dw::dds::ProcessCli cli("dw-bench-record: lossless recording rate through DDS beside raw Fast DDS");
        std::string rates = "2000,10000,40000,0";
        double seconds = 2.0;
        cli.app().add_option("--rates", rates, "publish rates to sweep [msg/s]; 0 = as fast as the publisher can");
        cli.app().add_option("--seconds", seconds, "publishing time per rate")->check(dw::cli::in({1, 3600, "s"}));
        cli.parse(argc, argv);
        dw::dds::DdsConfig cfg = cli.dds();
        if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "benchrec" + std::to_string(::getpid());

        std::printf(
            "| offered [msg/s] | achieved [msg/s] | raw Fast DDS received | recorder recorded | recorder lost (seq "
            "gaps) |\n");
        std::printf("|---|---|---|---|---|\n");
        std::stringstream list(rates);
        std::string item;
        while (std::getline(list, item, ',')) {
            const double rate = std::stod(item);  // 0: as fast as the publisher can
            const auto count = static_cast<std::uint64_t>((rate > 0 ? rate : 100000) * seconds);
            RawCounter raw(cfg);
            dw::dds::Participant rp(cfg, "recorder");
            dw::recorder::RecordOptions o;
            o.out = (std::filesystem::temp_directory_path() / "dw-bench-record.mcap").string();
            o.topics = {"stand/wrench"};
            o.writer.fsync = true;
            dw::recorder::Recorder rec(rp, o);
            std::vector<std::string> args{dw::executable_dir() + "/dw-probe",
                                          "pub",
                                          "stand/wrench",
                                          "--count",
                                          std::to_string(count),
                                          "--rate",
                                          item,
                                          "--wait-readers",
                                          "2",
                                          "--quiet"};
            for (const auto& a : dw::dds::to_args(cfg)) args.push_back(a);
            const auto t0 = std::chrono::steady_clock::now();
            dw::Subprocess pub({args, "", "", {}});
            std::atomic<bool> done{false};
            std::thread ticker([&] {
                while (!done) {
                    rec.tick();
                    std::this_thread::sleep_for(std::chrono::milliseconds(50));
                }
            });
            const auto status = pub.wait_for(std::chrono::minutes(10));
            if (status != 0) throw dw::RuntimeError("the publisher failed at rate " + item);
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() - 0.1;
            std::this_thread::sleep_for(std::chrono::milliseconds(500));
            done = true;
            ticker.join();
            rec.close();
            const auto s = rec.stats().front();
            std::printf("| %s | %.0f | %llu / %llu | %llu / %llu | %llu |\n", rate > 0 ? item.c_str() : "unthrottled",
                        static_cast<double>(count) / elapsed, static_cast<unsigned long long>(raw.count.load()),
                        static_cast<unsigned long long>(count), static_cast<unsigned long long>(s.recorded),
                        static_cast<unsigned long long>(count), static_cast<unsigned long long>(s.lost));
            std::fflush(stdout);
            std::filesystem::remove(o.out);
        }
        return 0;
    });
}
