#pragma once
// YAML configuration files with errors that say where: "lab.yaml:3:12: dds.domain: expected an
// integer". Loading is all-or-nothing; a missing optional key keeps its default.
#include <yaml-cpp/yaml.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/numbers.hpp"

namespace dw {

// The one way a YAML document is read: parse errors and duplicate keys (which yaml-cpp would
// otherwise resolve silently to the first) are dw::InputError "name:line:col: ...".
YAML::Node load_yaml(const std::string& text, const std::string& name);
// load_yaml() of a file's bytes (missing, directory, unreadable: one clear InputError).
YAML::Node load_yaml_file(const std::string& path, std::string_view what);

// The one form of a located error: "file:line:col: key: problem" at `node` (its position if known).
[[noreturn]] void fail_at_node(const std::string& file, const YAML::Node& node, const std::string& key,
                               const std::string& problem);
// The one unknown-key message: "unknown key 'x' (known: a, b)".
std::string unknown_key_problem(const std::string& key, const std::set<std::string>& known);
// The one unknown-key rule: a key of the mapping `map` (at `where`) not in `known` is
// "file:line:col: where.key: unknown key 'key' (known: a, b)"; nothing when `map` is not a mapping.
void require_known_keys(const std::string& file, const YAML::Node& map, const std::string& where,
                        const std::set<std::string>& known);

class ConfigFile {
public:
    ConfigFile() = default;  // empty: every key absent
    // Throws dw::InputError when the file is missing, a directory, unreadable or not valid YAML.
    static ConfigFile load(const std::string& path);
    static ConfigFile parse(const std::string& text, const std::string& name);

    const std::string& path() const { return path_; }
    bool empty() const { return !root_ || root_.IsNull(); }
    // The node at a dotted path ("dds.domain"; "" = the whole document), or an undefined node.
    YAML::Node at(const std::string& dotted) const;

    // Typed reads of an optional key: nullopt when absent, InputError when of the wrong type.
    // Numbers must lie in `range` (dw::Range: finite, the range named in the error).
    std::optional<long long> get_int(const std::string& dotted, const Range& range) const;
    std::optional<double> get_double(const std::string& dotted, const Range& range) const;
    std::optional<bool> get_bool(const std::string& dotted) const;
    std::optional<std::string> get_string(const std::string& dotted) const;
    std::optional<std::vector<std::string>> get_strings(const std::string& dotted) const;

    // Refuses a key of the mapping at `dotted` that is not in `known` ("file:line:col:
    // dds.domian: unknown key (known: ...)"); nothing when that mapping is absent.
    void require_keys(const std::string& dotted, const std::set<std::string>& known) const;

    // "file:line:col: key: problem" for a problem with a key (the key's position if known).
    [[noreturn]] void fail(const std::string& dotted, const std::string& problem) const;

private:
    std::string path_;
    YAML::Node root_;
};

}  // namespace dw
