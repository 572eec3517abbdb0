#include "core/cli.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <iostream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"

namespace dw::cli {
namespace {
constexpr const char* kRangeCheck = "dw-range";

bool is_numeric(const CLI::Option& o) {
    const std::string t = o.get_type_name();
    return t.rfind("FLOAT", 0) == 0 || t.rfind("INT", 0) == 0 || t.rfind("UINT", 0) == 0;
}

bool has_range(CLI::Option& o) {
    try {
        return o.get_validator(kRangeCheck) != nullptr;
    } catch (const CLI::OptionNotFound&) {
        return false;
    }
}

void require_ranges(CLI::App& app) {
    for (CLI::Option* o : app.get_options()) {
        if (is_numeric(*o) && !has_range(*o)) {
            throw std::logic_error(log::cat("program error: numeric option ", o->get_name(), " of '", app.get_name(),
                                            "' declares no range (dw::cli::in)"));
        }
    }
    for (CLI::App* sub : app.get_subcommands({})) require_ranges(*sub);
}

void require_config_file(CLI::App& app) {
    const CLI::Option* config = app.get_option_no_throw("--config");
    if (config != nullptr && config->count() > 0) require_readable_file(config->as<std::string>(), "--config");
}
}  // namespace

CLI::Validator in(const Range& r) {
    CLI::Validator v(
        [r](std::string& text) -> std::string {
            double value = 0;
            try {
                value = parse_number(text, "value");
            } catch (const InputError&) {
                return log::cat("'", text, "' is not a number");
            }
            return range_problem(value, r);
        },
        r.describe(), kRangeCheck);
    return v;
}

void configure(CLI::App& app, BaseOptions& base) {
    app.fallthrough();
    app.option_defaults()->always_capture_default();
    app.add_option("--config", base.config_path, "YAML configuration file")->type_name("FILE");
    app.add_option("--log-level", base.log_level, "trace, debug, info, warn, error or off")->type_name("LEVEL");
}

void parse(CLI::App& app, int argc, char** argv) {
    require_ranges(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        std::exit(app.exit(e));
    } catch (const CLI::CallForAllHelp& e) {
        std::exit(app.exit(e));
    } catch (const CLI::CallForVersion& e) {
        std::exit(app.exit(e));
    } catch (const CLI::ParseError& e) {
        throw InputError(std::string(e.what()) + " (see --help)");
    }
    require_config_file(app);
}

int run_main(const char* program, const std::function<int()>& body) {
    log::set_program(program);
    Shutdown::install();  // before any thread: every tool stops on SIGINT/SIGTERM the same way
    try {
        return body();
    } catch (const Stopped& e) {
        log::error(e.what());
        return kExitStopped;
    } catch (const InputError& e) {
        log::error(e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        log::error(e.what());
        return kExitRuntime;
    }
}

}  // namespace dw::cli
