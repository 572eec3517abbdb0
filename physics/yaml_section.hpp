#pragma once
// A strict reader of one YAML mapping, for the physics configuration and the effects' own
// sections: every key must be consumed (an unknown key is an error naming it), numbers are
// range-checked, and every error is located "file:line:col: path.key: problem".
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <exception>
#include <set>
#include <string>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"

namespace dw::physics {

// Reads one YAML mapping strictly: every key must be consumed, values are checked.
class Section {
public:
    Section(const YAML::Node& node, std::string path, const std::string& file)
        : node_(node), path_(std::move(path)), file_(file) {
        if (node_ && !node_.IsNull() && !node_.IsMap()) fail(node_, "expected a mapping of keys");
    }
    ~Section() noexcept(false) {
        if (std::uncaught_exceptions() > 0 || !node_ || node_.IsNull()) return;
        for (const auto& kv : node_) {
            const std::string key = kv.first.Scalar();
            if (!used_.count(key)) fail(kv.first, log::cat("unknown key '", key, "'"), key);
        }
    }
    YAML::Node get(const std::string& key) {
        used_.insert(key);
        if (!node_ || node_.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
        const YAML::Node& view = node_;
        return view[key];
    }
    void number(const std::string& key, double& out, double min, double max) {
        const YAML::Node n = get(key);
        if (!n) return;
        double v = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, v)) fail(n, "expected a number", key);
        const Range range{min, max};
        if (!range.contains(v)) fail(n, range_problem(v, range), key);
        out = v;
    }
    void integer(const std::string& key, int& out, int min, int max) {
        double v = out;
        number(key, v, min, max);
        if (v != std::floor(v)) fail(get(key), "expected a whole number", key);
        out = static_cast<int>(v);
    }
    void flag(const std::string& key, bool& out) {
        const YAML::Node n = get(key);
        if (!n) return;
        bool v = false;
        if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) fail(n, "expected true or false", key);
        out = v;
    }
    std::string text(const std::string& key, const std::string& fallback) {
        const YAML::Node n = get(key);
        if (!n) return fallback;
        if (!n.IsScalar()) fail(n, "expected a word", key);
        return n.Scalar();
    }
    const YAML::Node& node() const { return node_; }
    Section sub(const std::string& key) { return Section(get(key), path_.empty() ? key : path_ + "." + key, file_); }
    [[noreturn]] void fail(const YAML::Node& n, const std::string& what, const std::string& key = "") const {
        fail_at_node(file_, n, path_.empty() ? key : (key.empty() ? path_ : path_ + "." + key), what);
    }

private:
    YAML::Node node_;
    std::string path_;
    const std::string& file_;
    std::set<std::string> used_;
};

}  // namespace dw::physics
