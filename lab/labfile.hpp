#pragma once
// Lab files (downwash-lab/1): which processes make up the lab, on which host, with which
// arguments. Loaded strictly: a problem is an error naming file, line, column and key.
//
//   format: downwash-lab/1
//   vars: {formation: leader_follower3}          # {name} in run: is replaced (also {run_dir})
//   hosts:
//     local: {}                                  # this machine
//     pi: {launch: [ssh, pi@10.0.0.2], bin: /opt/downwash/bin}
//     mocap-pc: {}                               # no launch: the launcher prints the command
//   processes:
//     - name: stand_agent
//       host: pi
//       run: [dw-stand-agent, run, --sim]
//       restart: on-failure                      # never (default) or on-failure (up to 3 times)
//     - name: planner
//       run: [dw-planner, run, --formation, "{formation}"]
//       experiment: true                         # the lab run ends when this process ends
#include <map>
#include <string>
#include <vector>

namespace dw::lab {

inline constexpr const char* kLauncher = "dw-lab";  // never a process of a lab file: it would start itself

// Letters, digits, '_', '-' and '.', not starting with '.': a process name is a file name and a
// heartbeat name, never a path.
bool is_process_name(const std::string& name);

struct HostSpec {
    std::string name;
    std::vector<std::string> launch;  // command prefix that starts a process there (ssh, ip netns exec, ...)
    std::string bin;                  // the executables' folder there (default: this launcher's)
};

enum class Restart { never, on_failure };
inline constexpr const char* kRestartNames[] = {"never", "on-failure"};  // Restart's values in order

struct ProcessSpec {
    std::string name;
    std::string host = "local";
    std::vector<std::string> run;  // program name (a lab executable) and its arguments
    Restart restart = Restart::never;
    bool experiment = false;
};

struct LabFile {
    std::string path;
    std::map<std::string, std::string> vars;
    std::map<std::string, HostSpec> hosts;
    std::vector<ProcessSpec> processes;
};

// Throws dw::InputError "file:line:col: key: problem".
LabFile load_lab(const std::string& path);
LabFile parse_lab(const std::string& yaml, const std::string& name);

// {name} replaced by vars (unknown names are an error naming the process).
std::vector<std::string> expand(const ProcessSpec& p, const std::map<std::string, std::string>& vars);

}  // namespace dw::lab
