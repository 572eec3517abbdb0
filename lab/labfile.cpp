#include "lab/labfile.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <set>
#include <sstream>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"

namespace dw::lab {

namespace {

struct Ctx {
    std::string file;
    [[noreturn]] void fail(const YAML::Node& n, const std::string& key, const std::string& problem) const {
        fail_at_node(file, n, key, problem);
    }
    std::string str(const YAML::Node& n, const std::string& key) const {
        if (!n.IsScalar()) fail(n, key, "expected a string");
        return n.as<std::string>();
    }
    std::vector<std::string> strs(const YAML::Node& n, const std::string& key) const {
        if (!n.IsSequence()) fail(n, key, "expected a list of strings");
        std::vector<std::string> out;
        for (std::size_t i = 0; i < n.size(); ++i) out.push_back(str(n[i], log::cat(key, "[", i, "]")));
        return out;
    }
    void only(const YAML::Node& n, const std::string& where, const std::set<std::string>& keys) const {
        if (!n.IsMap()) fail(n, where, "expected a mapping");
        require_known_keys(file, n, where, keys);
    }
};

}  // namespace

// The name becomes a log file under the run folder and a heartbeat name: no paths.
bool is_process_name(const std::string& name) { return is_plain_name(name); }

LabFile parse_lab(const std::string& yaml, const std::string& name) {
    Ctx c{name};
    const YAML::Node root = load_yaml(yaml, name);
    LabFile lab;
    lab.path = name;
    if (!root.IsMap()) c.fail(root, "(document)", "expected a mapping with format, hosts and processes");
    c.only(root, "", {"format", "vars", "hosts", "processes"});
    if (!root["format"] || c.str(root["format"], "format") != "downwash-lab/1")
        c.fail(root["format"] ? root["format"] : root, "format", "expected downwash-lab/1");
    if (root["vars"]) {
        if (!root["vars"].IsMap()) c.fail(root["vars"], "vars", "expected a mapping of names to values");
        for (const auto& kv : root["vars"])
            lab.vars[kv.first.as<std::string>()] = c.str(kv.second, "vars." + kv.first.as<std::string>());
    }
    lab.hosts["local"] = {"local", {}, ""};
    if (root["hosts"]) {
        if (!root["hosts"].IsMap()) c.fail(root["hosts"], "hosts", "expected a mapping of host names");
        for (const auto& kv : root["hosts"]) {
            const auto h = kv.first.as<std::string>();
            const std::string where = "hosts." + h;
            HostSpec spec{h, {}, ""};
            if (!kv.second.IsNull()) {
                c.only(kv.second, where, {"launch", "bin"});
                if (kv.second["launch"]) spec.launch = c.strs(kv.second["launch"], where + ".launch");
                if (kv.second["bin"]) spec.bin = c.str(kv.second["bin"], where + ".bin");
            }
            if (h == "local" && !spec.launch.empty())
                c.fail(kv.second, where + ".launch", "the local host needs no launch prefix");
            lab.hosts[h] = spec;
        }
    }
    const auto procs = root["processes"];
    if (!procs || !procs.IsSequence() || procs.size() == 0)
        c.fail(procs ? procs : root, "processes", "expected a non-empty list");
    std::set<std::string> names;
    int experiments = 0;
    for (std::size_t i = 0; i < procs.size(); ++i) {
        const auto& n = procs[i];
        const std::string where = log::cat("processes[", i, "]");
        c.only(n, where, {"name", "host", "run", "restart", "experiment"});
        ProcessSpec p;
        if (!n["name"]) c.fail(n, where + ".name", "missing");
        p.name = c.str(n["name"], where + ".name");
        if (!is_process_name(p.name)) {
            c.fail(n["name"], where + ".name",
                   "'" + p.name + "' is not a process name (letters, digits, _ - and ., not starting with .)");
        }
        if (!names.insert(p.name).second) c.fail(n["name"], where + ".name", "'" + p.name + "' is used twice");
        if (n["host"]) p.host = c.str(n["host"], where + ".host");
        if (!lab.hosts.count(p.host)) c.fail(n["host"], where + ".host", "'" + p.host + "' is not under hosts");
        if (!n["run"]) c.fail(n, where + ".run", "missing");
        p.run = c.strs(n["run"], where + ".run");
        if (p.run.empty()) c.fail(n["run"], where + ".run", "empty");
        if (p.run[0].find('/') != std::string::npos || p.run[0].rfind("dw-", 0) != 0)
            c.fail(n["run"], where + ".run[0]", "'" + p.run[0] + "' is not a lab executable (dw-...)");
        if (p.run[0] == kLauncher)
            c.fail(n["run"], where + ".run[0]",
                   "a lab file cannot start the launcher (it would start itself without end)");
        if (n["restart"]) {
            const auto r = c.str(n["restart"], where + ".restart");
            if (r == "never") p.restart = Restart::never;
            else if (r == "on-failure") p.restart = Restart::on_failure;
            else c.fail(n["restart"], where + ".restart", "expected never or on-failure");
        }
        if (n["experiment"]) {
            if (!n["experiment"].IsScalar() ||
                (n["experiment"].as<std::string>() != "true" && n["experiment"].as<std::string>() != "false"))
                c.fail(n["experiment"], where + ".experiment", "expected true or false");
            p.experiment = n["experiment"].as<std::string>() == "true";
            experiments += p.experiment;
        }
        lab.processes.push_back(p);
    }
    if (experiments > 1) c.fail(procs, "processes", "more than one process has experiment: true");
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
