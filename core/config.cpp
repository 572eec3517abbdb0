#include "core/config.hpp"

#include <fstream>
#include <sstream>

#include "core/log.hpp"

namespace dw {

ConfigFile ConfigFile::load(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw InputError(log::cat("config ", path, ": cannot read the file"));
    std::stringstream text;
    text << in.rdbuf();
    return parse(text.str(), path);
}

ConfigFile ConfigFile::parse(const std::string& text, const std::string& name) {
    ConfigFile c;
    c.path_ = name;
    try {
        c.root_ = YAML::Load(text);
    } catch (const YAML::ParserException& e) {
        throw InputError(log::cat(name, ":", e.mark.line + 1, ":", e.mark.column + 1,
                                  ": not valid YAML: ", e.msg));
    }
    if (c.root_ && !c.root_.IsNull() && !c.root_.IsMap()) {
        throw InputError(log::cat(name, ":1:1: the top level must be a mapping of keys"));
    }
    return c;
}

YAML::Node ConfigFile::at(const std::string& dotted) const {
    if (empty()) return YAML::Node(YAML::NodeType::Undefined);
    YAML::Node node;
    node.reset(root_);
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

void ConfigFile::fail(const std::string& dotted, const std::string& problem) const {
    const YAML::Node node = at(dotted);
    if (node && node.Mark().line >= 0) {
        throw InputError(log::cat(path_, ":", node.Mark().line + 1, ":", node.Mark().column + 1,
                                  ": ", dotted, ": ", problem));
    }
    throw InputError(log::cat(path_, ": ", dotted, ": ", problem));
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

std::optional<long long> ConfigFile::get_int(const std::string& d) const {
    return read_scalar<long long>(*this, d, "an integer");
}
std::optional<double> ConfigFile::get_double(const std::string& d) const {
    return read_scalar<double>(*this, d, "a number");
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
