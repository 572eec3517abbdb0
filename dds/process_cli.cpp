#include "dds/process_cli.hpp"

#include "core/log.hpp"

namespace dw::dds {

ProcessCli::ProcessCli(const std::string& description) : app_(description) {
    cli::configure(app_, base_);
    add_cli_options(app_, dds_cli_);
    app_.add_option(
            "--clock-offset", clock_offset_s_,
            "simulation: this process's clock runs S seconds ahead of the host's (a hidden clock error, for tests)")
        ->type_name("S")
        ->check(cli::in(kClockOffsetRange));
}

void ProcessCli::parse(int argc, char** argv) {
    cli::parse(app_, argc, argv);
    log::set_level(log::parse_level(base_.log_level));
    if (!base_.config_path.empty()) config_ = ConfigFile::load(base_.config_path);
    dds_ = resolve(dds_cli_, config_);
    offset_clock_ = OffsetClock(SystemClock::instance(), from_seconds(clock_offset_s_));
}

std::vector<std::string> child_args(const DdsConfig& dds, const std::string& log_level) {
    std::vector<std::string> a = to_args(dds);
    a.insert(a.end(), {"--log-level", log_level});
    return a;
}

std::vector<std::string> ProcessCli::dds_args() const { return child_args(dds_, base_.log_level); }

}  // namespace dw::dds
