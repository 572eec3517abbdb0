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

std::vector<std::string> ProcessCli::dds_args() const {
    std::vector<std::string> a = to_args(dds_);
    a.insert(a.end(), {"--log-level", base_.log_level});
    return a;
}

}  // namespace dw::dds
