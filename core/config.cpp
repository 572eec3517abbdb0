#include "core/config.hpp"

#include <set>
#include <sstream>

#include "core/files.hpp"
#include "core/log.hpp"

namespace dw {
namespace {
void require_unique_keys(const YAML::Node& node, const std::string& name) {
    if (node.IsSequence()) {
        for (const auto& item : node) require_unique_keys(item, name);
        return;
    }
    if (!node.IsMap()) return;
    std::set<std::string> seen;
    for (const auto& kv : node) {
        const std::string key = kv.first.Scalar();
        if (kv.first.IsScalar() && !seen.insert(key).second) {
            throw InputError(log::cat(name, ":", kv.first.Mark().line + 1, ":", kv.first.Mark().column + 1, ": key '",
                                      key, "' appears twice in the same mapping"));
        }
        require_unique_keys(kv.second, name);
    }
}
}  // namespace

YAML::Node load_yaml(const std::string& text, const std::string& name, std::string_view language) {
    YAML::Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::ParserException& e) {
        throw InputError(
            log::cat(name, ":", e.mark.line + 1, ":", e.mark.column + 1, ": not valid ", language, ": ", e.msg));
    }
    require_unique_keys(root, name);
    return root;
}

YAML::Node load_yaml_file(const std::string& path, std::string_view what) {
    return load_yaml(read_file(path, what), path);
}

ConfigFile ConfigFile::load(const std::string& path) { return parse(read_file(path, "config"), path); }

ConfigFile ConfigFile::parse(const std::string& text, const std::string& name) {
    ConfigFile c;
    c.path_ = name;
    c.root_ = load_yaml(text, name);
    if (c.root_ && !c.root_.IsNull() && !c.root_.IsMap()) {
        throw InputError(log::cat(name, ":1:1: the top level must be a mapping of keys"));
    }
    return c;
}

std::string located(const std::string& file, const YAML::Node& node, const std::string& key,
                    const std::string& problem) {
    const std::string what = key.empty() ? problem : key + ": " + problem;  // "" = the document itself
    if (node && node.Mark().line >= 0)
        return log::cat(file, ":", node.Mark().line + 1, ":", node.Mark().column + 1, ": ", what);
    return log::cat(file, ": ", what);
}

void fail_at_node(const std::string& file, const YAML::Node& node, const std::string& key, const std::string& problem) {
    throw InputError(located(file, node, key, problem));
}

std::string unknown_key_problem(const std::string& key, const std::set<std::string>& known) {
    return log::cat("unknown key '", key, "' (known: ", log::join(known), ")");
}

}  // namespace dw
