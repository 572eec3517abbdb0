#include "core/cli.hpp"

#include <cstdlib>
#include <iostream>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::cli {

void configure(CLI::App& app, BaseOptions& base) {
    app.fallthrough();
    app.option_defaults()->always_capture_default();
    app.add_option("--config", base.config_path, "YAML configuration file")->type_name("FILE");
    app.add_option("--log-level", base.log_level, "trace, debug, info, warn, error or off")
        ->type_name("LEVEL");
}

void parse(CLI::App& app, int argc, char** argv) {
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
}

int run_main(const char* program, const std::function<int()>& body) {
    log::set_program(program);
    try {
        return body();
    } catch (const InputError& e) {
        log::error(e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        log::error(e.what());
        return kExitRuntime;
    }
}

}  // namespace dw::cli
