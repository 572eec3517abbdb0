#pragma once
// The lab launcher: starts a lab file's processes as separate OS processes (here, or on other
// hosts through their launch prefix — ssh, ip netns exec — or prints the command to run there),
// watches them (heartbeats: one live status line per process with its rate, drops and heartbeat
// age; restarts on failure when asked), shows the experiment's progress (legs, bar, ETA), and
// stops everything cleanly when the experiment ends or on Ctrl-C.
#include <functional>
#include <map>
#include <stop_token>
#include <string>
#include <vector>

#include "dds/config.hpp"
#include "lab/labfile.hpp"

namespace dw::lab {

struct LaunchOptions {
    std::string run_dir;                          // logs/ and {run_dir}
    std::map<std::string, std::string> vars;      // overrides the lab file's vars
    std::vector<std::string> dds_args;            // appended to every process (domain, namespace, profile, ...)
    bool live = true;                             // redraw the status block (a terminal) or print it every 10 s
    double stop_grace_s = 15;                     // SIGINT, then SIGKILL after this
    std::function<void(const std::string&)> say;  // one line per event
    std::stop_token stop;                         // stops every process (SIGINT, then SIGKILL after the grace)
};

struct LaunchResult {
    int experiment_status = -1;  // the experiment process's exit status
    std::string phase;           // its last phase seen (DONE, ABORTED, ...)
    bool done = false;           // that phase was DONE
    // The experiment ended DONE and its process exited 0.
    bool succeeded() const { return experiment_status == 0 && done; }
    unsigned legs_flown = 0, legs_total = 0;
    std::vector<std::string> printed;  // commands for hosts the launcher cannot start
    std::map<std::string, int> restarts;
};

// Runs until the experiment process ends (or, without one, until Ctrl-C). Throws
// dw::InputError for a bad lab file or variable, dw::RuntimeError when a process cannot start.
LaunchResult launch(const LabFile& lab, const LaunchOptions& o, const dds::DdsConfig& monitor);

// The progress bar: "[#######.............] 7/20 legs  35 %  ETA 1:05".
std::string progress_bar(unsigned flown, unsigned total, double progress, double eta_s, int width = 30);

}  // namespace dw::lab
