#pragma once
// The command line every lab process starts with: the house options (--help, --config,
// --log-level) and the DDS options, parsed, the log level applied, the config file loaded and
// the DDS configuration resolved in one call.
#include <string>

#include "core/cli.hpp"
#include "core/clock.hpp"
#include "core/config.hpp"
#include "dds/config.hpp"
#include "dds/time.hpp"

namespace dw::dds {

using dw::kClockOffsetRange;  // core/clock.hpp

class ProcessCli {
public:
    explicit ProcessCli(const std::string& description);
    CLI::App& app() { return app_; }
    // Throws dw::InputError for bad usage, an unreadable/malformed config or a bad DDS setting.
    void parse(int argc, char** argv);

    const cli::BaseOptions& base() const { return base_; }
    const ConfigFile& config() const { return config_; }
    const DdsConfig& dds() const { return dds_; }
    // The process's wall clock: the system's, or shifted by --clock-offset (a simulated clock error).
    Clock& clock() const { return clock_offset_s_ == 0 ? static_cast<Clock&>(SystemClock::instance()) : offset_clock_; }
    // The resolved DDS settings and the log level as flags, to hand to a child process.
    std::vector<std::string> dds_args() const;

private:
    CLI::App app_;
    cli::BaseOptions base_;
    DdsCliOptions dds_cli_;
    ConfigFile config_;
    DdsConfig dds_;
    double clock_offset_s_ = 0;
    mutable OffsetClock offset_clock_{SystemClock::instance(), 0};
};

}  // namespace dw::dds
