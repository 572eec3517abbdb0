#pragma once
// The one CLI convention of every lab executable, on CLI11: --help, --config, --log-level on the
// root (accepted after a subcommand too), errors as one line and exit code 2.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>

#include "core/numbers.hpp"

namespace dw::cli {

struct BaseOptions {
    std::string config_path;  // "" = none
    std::string log_level = "info";
};

// A CLI11 app with the house settings and --config/--log-level bound to `base`.
void configure(CLI::App& app, BaseOptions& base);

// The check every numeric option carries: its value lies in r (NaN and inf never do), and the
// error names the range. parse() refuses to run an app with a numeric option that lacks one.
CLI::Validator in(const Range& r);

// Parses argv. Every numeric option (FLOAT, INT, UINT) must carry `in(...)`: a program error
// (std::logic_error) otherwise, so no tool can take an unchecked number. --config must name a
// readable file. --help/--version print and end the process with 0; a usage error throws
// dw::InputError with one line naming the option.
void parse(CLI::App& app, int argc, char** argv);

// Runs a process body with the house error handling: installs Shutdown (SIGINT/SIGTERM), maps
// dw::Stopped to one line and exit 130, sets the program name for logs, maps
// dw::InputError to one line and exit 2, any other exception to one line and exit 1.
int run_main(const char* program, const std::function<int()>& body);

}  // namespace dw::cli
