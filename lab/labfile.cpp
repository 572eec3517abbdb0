#include "lab/labfile.hpp"

#include <algorithm>
#include <set>

#include "core/text.hpp"
#include "core/config.hpp"
#include "core/keys.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"

namespace dw::lab {

// The name becomes a log file under the run folder and a heartbeat name: no paths.
bool is_process_name(const std::string& name) { return is_plain_name(name); }

namespace {

constexpr const char* kFormat = "downwash-lab/1";

// Why `run` cannot start a process ("" when it can).
std::string run_problem(const std::vector<std::string>& run) {
    if (run.empty()) return "empty";
    if (run[0].find('/') != std::string::npos || run[0].rfind("dw-", 0) != 0)
        return "'" + run[0] + "' is not a lab executable (dw-...)";
    if (run[0] == kLauncher) return "a lab file cannot start the launcher (it would start itself without end)";
    return "";
}

template <class Map>
std::vector<std::string> keys_of(const Map& m) {
    std::vector<std::string> out;
    for (const auto& [name, value] : m) out.push_back(name);
    return out;
}

void var_keys(KeyVisitor& k, std::map<std::string, std::string>& vars) {
    auto names = keys_of(vars);
    k.names(names);
    for (const auto& n : names) k.text(n, vars[n]);
}

void host_keys(KeyVisitor& k, std::map<std::string, HostSpec>& hosts) {
    auto names = keys_of(hosts);
    k.names(names);
    for (const auto& n : names) {
        HostSpec& h = hosts[n];
        h.name = n;
        k.section(n, [&](KeyVisitor& s) {
            s.texts("launch", h.launch);
            s.text("bin", h.bin);
            s.require(n != "local" || h.launch.empty(), "launch", "the local host needs no launch prefix");
        });
    }
}

void process_keys(KeyVisitor& k, ProcessSpec& p, const LabFile& lab) {
    k.require(k.has("name"), "name", "missing");
    k.text("name", p.name);
    k.require(is_process_name(p.name), "name",
              "'" + quote_bytes(p.name, kQuotedBytes) +
                  "' is not a process name (letters, digits, _ - and ., not starting with .)");
    k.text("host", p.host);
    k.require(lab.hosts.count(p.host) > 0, "host", "'" + p.host + "' is not under hosts");
    k.require(k.has("run"), "run", "missing");
    k.texts("run", p.run);
    const std::string problem = run_problem(p.run);
    k.require(problem.empty(), "run", problem);
    k.enumeration("restart", p.restart, kRestartNames, "restart policy");
    k.flag("experiment", p.experiment);
}

// What a process writes: the value of its `--out` (as written, before the variables: two processes
// naming the same text name the same file on the same host).
std::optional<std::string> output_of(const ProcessSpec& p) {
    constexpr std::string_view kOut = "--out";
    for (std::size_t i = 0; i < p.run.size(); ++i) {
        if (p.run[i] == kOut && i + 1 < p.run.size()) return p.run[i + 1];
        if (p.run[i].rfind(std::string(kOut) + "=", 0) == 0) return p.run[i].substr(kOut.size() + 1);
    }
    return std::nullopt;
}

// Every key of a lab file, declared once (core/keys.hpp).
void lab_keys(KeyVisitor& k, LabFile& lab) {
    k.required_constant("format", kFormat);
    k.section("vars", [&](KeyVisitor& v) { var_keys(v, lab.vars); });
    k.section("hosts", [&](KeyVisitor& h) { host_keys(h, lab.hosts); });
    k.require(k.has("processes"), "processes", "expected a non-empty list");
    std::size_t count = lab.processes.size();
    std::set<std::string> names;
    std::map<std::pair<std::string, std::string>, std::string> outputs;  // (host, --out) -> process
    k.list("processes", count, [&](KeyVisitor& item, std::size_t i) {
        if (lab.processes.size() <= i) lab.processes.resize(i + 1);
        ProcessSpec& p = lab.processes[i];
        process_keys(item, p, lab);
        item.require(names.insert(p.name).second, "name", "'" + p.name + "' is used twice");
        if (const auto out = output_of(p)) {
            const auto [at, fresh] = outputs.emplace(std::pair{p.host, *out}, p.name);
            item.require(fresh, "run", "--out '" + *out + "' is also " + at->second + "'s: two writers, one file");
        }
    });
    k.require(count > 0, "processes", "expected a non-empty list");
    const auto experiments = std::ranges::count_if(lab.processes, [](const ProcessSpec& p) { return p.experiment; });
    k.require(experiments <= 1, "processes", "more than one process has experiment: true");
}

}  // namespace

LabFile parse_lab(const std::string& yaml, const std::string& name) {
    LabFile lab;
    lab.path = name;
    lab.hosts["local"] = {"local", {}, ""};
    read_keys(load_yaml(yaml, name), name, [&](KeyVisitor& k) { lab_keys(k, lab); });
    return lab;
}

LabFile load_lab(const std::string& path) { return parse_lab(read_file(path, "lab file"), path); }

std::vector<std::string> expand(const ProcessSpec& p, const std::map<std::string, std::string>& vars) {
    std::vector<std::string> out;
    for (const auto& arg : p.run) {
        std::string r;
        for (std::size_t i = 0; i < arg.size();) {
            if (arg[i] == '{') {
                const auto close = arg.find('}', i);
                if (close == std::string::npos)
                    throw InputError(log::cat("process ", p.name, ": '", arg, "': unclosed {"));
                const auto key = arg.substr(i + 1, close - i - 1);
                const auto it = vars.find(key);
                if (it == vars.end())
                    throw InputError(
                        log::cat("process ", p.name, ": '{", key, "}' is not a variable (vars: or --var)"));
                r += it->second;
                i = close + 1;
            } else {
                r += arg[i++];
            }
        }
        out.push_back(r);
    }
    return out;
}

}  // namespace dw::lab
