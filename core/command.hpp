#pragma once
// The one way a lab tool is written: a list of commands. A command binds its options to its own
// fields when it is added and does its work when it is run; run_commands adds a tool's commands,
// parses the line once and runs the one the line chose. A tool's main.cpp is its commands and one
// run_commands call (what they share — the DDS settings, a --physics on the root — each command is
// given when it is made).
#include <CLI/CLI.hpp>
#include <functional>
#include <vector>

namespace dw::cli {

class Command {
public:
    virtual ~Command() = default;
    // Registers the command on the tool's app and binds its options; returns where they are: its
    // subcommand, or app itself for the tool's main command (run when no subcommand is given).
    virtual CLI::App* add(CLI::App& app) = 0;
    // Its body, once the whole line is parsed and checked; the process's exit code.
    virtual int run() = 0;
};

// Adds the commands to app in order, calls `parse` (cli::parse, or a DDS tool's ProcessCli::parse,
// and what the tool sets up from its root options), then runs the command the line chose: the one
// whose subcommand was given, else the main command. With neither (no main command, and the app
// not requiring a subcommand) a std::logic_error: a program error, not the user's.
int run_commands(CLI::App& app, const std::vector<Command*>& commands, const std::function<void()>& parse);

}  // namespace dw::cli
