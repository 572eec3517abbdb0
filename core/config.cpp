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

YAML::Node load_yaml(const std::string& text, const std::string& name) {
    YAML::Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::ParserException& e) {
        throw InputError(log::cat(name, ":", e.mark.line + 1, ":", e.mark.column + 1, ": not valid YAML: ", e.msg));
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

YAML::Node ConfigFile::at(const std::string& dotted) const {
    if (empty()) return YAML::Node(YAML::NodeType::Undefined);
    YAML::Node node;
    node.reset(root_);
    if (dotted.empty()) return node;  // the whole document
    std::size_t start = 0;
    while (start <= dotted.size()) {
        const std::size_t dot = dotted.find('.', start);
        const std::string key = dotted.substr(start, dot == std::string::npos ? dot : dot - start);
        if (!node.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
        // Lookup through a const node: a non-const operator[] would insert the key.
        const YAML::Node& view = node;
        YAML::Node child = view[key];
        if (!child) return YAML::Node(YAML::NodeType::Undefined);
        node.reset(child);
        if (dot == std::string::npos) break;
        start = dot + 1;
    }
    return node;
}

void fail_at_node(const std::string& file, const YAML::Node& node, const std::string& key, const std::string& problem) {
    if (node && node.Mark().line >= 0) {
        throw InputError(
            log::cat(file, ":", node.Mark().line + 1, ":", node.Mark().column + 1, ": ", key, ": ", problem));
    }
    throw InputError(log::cat(file, ": ", key, ": ", problem));
}

std::string unknown_key_problem(const std::string& key, const std::set<std::string>& known) {
    return log::cat("unknown key '", key, "' (known: ", log::join(known), ")");
}

void require_known_keys(const std::string& file, const YAML::Node& map, const std::string& where,
                        const std::set<std::string>& known) {
    if (!map || !map.IsMap()) return;
    for (const auto& kv : map) {
        const std::string key = kv.first.Scalar();
        if (known.count(key)) continue;
        fail_at_node(file, kv.first, where.empty() ? key : where + "." + key, unknown_key_problem(key, known));
    }
}

void ConfigFile::require_keys(const std::string& dotted, const std::set<std::string>& known) const {
    require_known_keys(path_, at(dotted), dotted, known);
}

void ConfigFile::fail(const std::string& dotted, const std::string& problem) const {
    fail_at_node(path_, at(dotted), dotted, problem);
}

namespace {
template <class T>
std::optional<T> read_scalar(const ConfigFile& c, const std::string& dotted, const char* what) {
    const YAML::Node node = c.at(dotted);
    if (!node || node.IsNull()) return std::nullopt;
    if (!node.IsScalar()) c.fail(dotted, log::cat("expected ", what));
    try {
        return node.as<T>();
    } catch (const YAML::Exception&) {
        c.fail(dotted, log::cat("expected ", what, ", got '", node.Scalar(), "'"));
    }
}
}  // namespace

std::optional<long long> ConfigFile::get_int(const std::string& d, const Range& range) const {
    const auto v = read_scalar<long long>(*this, d, "an integer");
    if (v && !range.contains(static_cast<double>(*v))) fail(d, range_problem(static_cast<double>(*v), range));
    return v;
}
std::optional<double> ConfigFile::get_double(const std::string& d, const Range& range) const {
    const auto v = read_scalar<double>(*this, d, "a number");
    if (v && !range.contains(*v)) fail(d, range_problem(*v, range));
    return v;
}
std::optional<bool> ConfigFile::get_bool(const std::string& d) const {
    return read_scalar<bool>(*this, d, "true or false");
}
std::optional<std::string> ConfigFile::get_string(const std::string& d) const {
    return read_scalar<std::string>(*this, d, "a string");
}

std::optional<std::vector<std::string>> ConfigFile::get_strings(const std::string& dotted) const {
    const YAML::Node node = at(dotted);
    if (!node || node.IsNull()) return std::nullopt;
    if (!node.IsSequence()) fail(dotted, "expected a list of strings");
    std::vector<std::string> out;
    for (const auto& item : node) {
        if (!item.IsScalar()) fail(dotted, "expected a list of strings");
        out.push_back(item.Scalar());
    }
    return out;
}

}  // namespace dw
