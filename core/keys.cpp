#include "core/keys.hpp"

#include <cmath>
#include <optional>
#include <set>

#include "core/config.hpp"
#include "core/log.hpp"

namespace dw {
namespace {

// Reads one mapping strictly; finish() refuses the keys nothing visited.
class Reader final : public KeyVisitor {
public:
    Reader(const YAML::Node& node, std::string path, const std::string& file)
        : node_(node), path_(std::move(path)), file_(file) {
        if (node_ && !node_.IsNull() && !node_.IsMap()) fail(node_, "", "expected a mapping of keys");
    }
    void finish(const std::string& unknown_hint) const {
        if (!node_ || node_.IsNull()) return;
        for (const auto& kv : node_) {
            const std::string key = kv.first.Scalar();
            if (used_.count(key)) continue;
            fail(kv.first, key,
                 unknown_hint.empty() ? unknown_key_problem(key, used_)
                                      : log::cat("unknown key '", key, "'", unknown_hint));
        }
    }

    void number(const std::string& key, double& v, const Range& r) override {
        const YAML::Node n = get(key);
        if (!n) return;
        double x = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, x)) fail(n, key, "expected a number");
        if (!r.contains(x)) fail(n, key, range_problem(x, r));
        v = x;
    }
    void integer(const std::string& key, int& v, const Range& r) override {
        double x = v;
        number(key, x, r);
        if (x != std::floor(x)) fail(get(key), key, "expected a whole number");
        v = static_cast<int>(x);
    }
    void flag(const std::string& key, bool& v) override {
        const YAML::Node n = get(key);
        if (!n) return;
        if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) fail(n, key, "expected true or false");
    }
    void text(const std::string& key, std::string& v) override {
        if (const auto word = word_at(key)) v = *word;
    }
    bool has(const std::string& key) override { return static_cast<bool>(get(key)); }
    void choice(const std::string& key, int& v, std::span<const char* const> names, const std::string& what,
                const std::string& note) override {
        const auto word = word_at(key);
        if (!word) return;
        for (std::size_t i = 0; i < names.size(); ++i)
            if (*word == names[i]) v = static_cast<int>(i);
        if (*word != names[static_cast<std::size_t>(v)])
            fail(get(key), key,
                 log::cat("unknown ", what, " '", *word, "' (expected ", log::alternatives(names), note, ")"));
    }
    void numbers(const std::string& key, std::span<double> v, const Range& r, const std::string& shape) override {
        const YAML::Node n = get(key);
        if (!n) return;
        if (!n.IsSequence() || n.size() != v.size()) fail(n, key, shape);
        for (std::size_t i = 0; i < v.size(); ++i) {
            double x = 0;
            if (!YAML::convert<double>::decode(n[i], x)) fail(n, key, shape);
            if (!r.contains(x)) fail(n, key, range_problem(x, r));
            v[i] = x;
        }
    }
    void constant(const std::string& key, const std::string& value) override {
        const auto word = word_at(key);
        if (word && *word != value) fail(get(key), key, log::cat("expected ", value));
    }
    void section(const std::string& key, const Body& body, const std::string& unknown_hint) override {
        Reader inner(get(key), path_.empty() ? key : path_ + "." + key, file_);
        body(inner);
        inner.finish(unknown_hint);
    }
    void require(bool ok, const std::string& key, const std::string& problem) override {
        if (!ok) fail(get(key), key, problem);
    }

private:
    YAML::Node get(const std::string& key) {
        used_.insert(key);
        if (!node_ || node_.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
        const YAML::Node& view = node_;  // a const lookup never inserts the key
        return view[key];
    }
    // The scalar at key, or nullopt when absent (an empty scalar is a word like any other).
    std::optional<std::string> word_at(const std::string& key) {
        const YAML::Node n = get(key);
        if (!n) return std::nullopt;
        if (!n.IsScalar()) fail(n, key, "expected a word");
        return n.Scalar();
    }
    // At the key's value, or at the mapping when the key is absent.
    [[noreturn]] void fail(const YAML::Node& n, const std::string& key, const std::string& problem) const {
        fail_at_node(file_, n ? n : node_, path_.empty() ? key : (key.empty() ? path_ : path_ + "." + key), problem);
    }

    YAML::Node node_;
    std::string path_;
    const std::string& file_;
    std::set<std::string> used_;
};

class Writer final : public KeyVisitor {
public:
    explicit Writer(YAML::Emitter& out) : out_(out) {}
    void number(const std::string& key, double& v, const Range&) override {
        out_ << YAML::Key << key << YAML::Value << v;
    }
    void integer(const std::string& key, int& v, const Range&) override {
        out_ << YAML::Key << key << YAML::Value << v;
    }
    void flag(const std::string& key, bool& v) override { out_ << YAML::Key << key << YAML::Value << v; }
    void text(const std::string& key, std::string& v) override { out_ << YAML::Key << key << YAML::Value << v; }
    bool has(const std::string&) override { return true; }
    void choice(const std::string& key, int& v, std::span<const char* const> names, const std::string&,
                const std::string&) override {
        out_ << YAML::Key << key << YAML::Value << names[static_cast<std::size_t>(v)];
    }
    void numbers(const std::string& key, std::span<double> v, const Range&, const std::string&) override {
        out_ << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
        for (double x : v) out_ << x;
        out_ << YAML::EndSeq;
    }
    void constant(const std::string& key, const std::string& value) override {
        out_ << YAML::Key << key << YAML::Value << value;
    }
    void section(const std::string& key, const Body& body, const std::string&) override {
        out_ << YAML::Key << key << YAML::Value << YAML::BeginMap;
        body(*this);
        out_ << YAML::EndMap;
    }
    void require(bool, const std::string&, const std::string&) override {}

private:
    YAML::Emitter& out_;
};

}  // namespace

void read_keys(const YAML::Node& root, const std::string& file, const KeyVisitor::Body& body) {
    Reader r(root, "", file);
    body(r);
    r.finish("");
}

void write_keys(YAML::Emitter& out, const KeyVisitor::Body& body) {
    Writer w(out);
    out << YAML::BeginMap;
    body(w);
    out << YAML::EndMap;
}

}  // namespace dw
