#pragma once
// YAML configuration files with errors that say where: "lab.yaml:3:12: dds.domain: expected a
// number". Loading is all-or-nothing; a missing optional key keeps its default.
#include <yaml-cpp/yaml.h>

#include <set>
#include <string>

#include "core/errors.hpp"
#include "core/numbers.hpp"

namespace dw {

// The one way a YAML document is read: parse errors and duplicate keys (which yaml-cpp would
// otherwise resolve silently to the first) are dw::InputError "name:line:col: ...".
// `language` names the syntax in that message ("not valid JSON" for a JSON document).
YAML::Node load_yaml(const std::string& text, const std::string& name, std::string_view language = "YAML");
// load_yaml() of a file's bytes (missing, directory, unreadable: one clear InputError).
YAML::Node load_yaml_file(const std::string& path, std::string_view what);

// The one form of a located error: "file:line:col: key: problem" at `node` (its position if known).
std::string located(const std::string& file, const YAML::Node& node, const std::string& key,
                    const std::string& problem);
[[noreturn]] void fail_at_node(const std::string& file, const YAML::Node& node, const std::string& key,
                               const std::string& problem);
// The one unknown-key message: "unknown key 'x' (known: a, b)".
std::string unknown_key_problem(const std::string& key, const std::set<std::string>& known);

// A configuration file: its name and its YAML document, whose sections each reader takes through
// core/keys.hpp (read_section), with located errors.
class ConfigFile {
public:
    ConfigFile() = default;  // empty: every key absent
    // Throws dw::InputError when the file is missing, a directory, unreadable or not valid YAML.
    static ConfigFile load(const std::string& path);
    static ConfigFile parse(const std::string& text, const std::string& name);

    const std::string& path() const { return path_; }
    bool empty() const { return !root_ || root_.IsNull(); }
    const YAML::Node& root() const { return root_; }

private:
    std::string path_;
    YAML::Node root_;
};

}  // namespace dw
