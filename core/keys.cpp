#include "core/keys.hpp"

#include <cmath>
#include <optional>
#include <set>

#include "core/config.hpp"
#include "core/log.hpp"
#include "core/names.hpp"

namespace dw {
namespace {

// The first rule a document breaks (require()), reported once every key is known: a misspelt key
// explains the rules it breaks, so unknown keys come first.
using BrokenRule = std::optional<std::string>;

// Reads one mapping strictly; finish() refuses the keys nothing visited.
class Reader final : public KeyVisitor {
public:
    Reader(const YAML::Node& node, std::string path, const std::string& file, BrokenRule& broken)
        : node_(node), path_(std::move(path)), file_(file), broken_(broken) {
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

    // Visits `body` on this mapping, then refuses the keys it did not visit.
    void visit(const Body& body, const std::string& unknown_hint) {
        body(*this);
        finish(unknown_hint);
    }

    void number(const std::string& key, double& v, const Range& r) override { scalar(key, v, r, "a number"); }
    void integer(const std::string& key, int& v, const Range& r) override {
        double x = v;
        scalar(key, x, r, "an integer");
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
    void texts(const std::string& key, std::vector<std::string>& v) override {
        const YAML::Node n = get(key);
        if (!n) return;
        if (!n.IsSequence()) fail(n, key, "expected a list of words");
        std::vector<std::string> out;
        for (const auto& item : n) {
            if (!item.IsScalar()) fail(item, key, "expected a list of words");
            out.push_back(item.Scalar());
        }
        v = std::move(out);
    }
    bool has(const std::string& key) override { return static_cast<bool>(get(key)); }
    void choice(const std::string& key, int& v, std::span<const char* const> names, const std::string& what,
                const std::string& note) override {
        const auto word = word_at(key);
        if (!word) return;
        const auto i = find_name(names, *word);
        if (!i) fail(get(key), key, unknown_name_problem(what, *word, names, note));
        v = static_cast<int>(*i);
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
    void table(const std::string& key, std::span<double> v, std::size_t cols, const Range& r,
               const std::string& shape) override {
        const YAML::Node n = get(key);
        if (!n) return;
        const std::size_t rows = v.size() / cols;
        if (!n.IsSequence() || n.size() != rows) fail(n, key, shape);
        for (std::size_t i = 0; i < rows; ++i) {
            const YAML::Node row = n[i];
            if (!row.IsSequence() || row.size() != cols) fail(row, log::cat(key, "[", i, "]"), shape);
            for (std::size_t j = 0; j < cols; ++j)
                element(row[j], log::cat(key, "[", i, "][", j, "]"), v[i * cols + j], r);
        }
    }
    void constant(const std::string& key, const std::string& value) override {
        const auto word = word_at(key);
        if (word && *word != value) fail(get(key), key, log::cat("expected ", value));
    }
    void section(const std::string& key, const Body& body, const std::string& unknown_hint) override {
        Reader inner(get(key), where(key), file_, broken_);
        inner.visit(body, unknown_hint);
    }
    void require(bool ok, const std::string& key, const std::string& problem) override {
        if (!ok && !broken_) broken_ = located(file_, at_or_here(get(key)), where(key), problem);
    }
    void names(std::vector<std::string>& v) override {
        v.clear();
        if (!node_ || node_.IsNull()) return;
        for (const auto& kv : node_) v.push_back(kv.first.Scalar());
    }
    void list(const std::string& key, std::size_t& count, const Item& item) override {
        const YAML::Node n = get(key);
        count = 0;
        if (!n || n.IsNull()) return;
        if (!n.IsSequence()) fail(n, key, "expected a list");
        count = n.size();
        for (std::size_t i = 0; i < count; ++i) {
            Reader inner(n[i], log::cat(where(key), "[", i, "]"), file_, broken_);
            inner.visit([&](KeyVisitor& k) { item(k, i); }, "");
        }
    }

private:
    void element(const YAML::Node& n, const std::string& key, double& v, const Range& r) const {
        double x = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, x)) fail(n, key, "expected a number");
        if (!r.contains(x)) fail(n, key, range_problem(x, r));
        v = x;
    }
    void scalar(const std::string& key, double& v, const Range& r, const char* what) {
        const YAML::Node n = get(key);
        if (!n) return;
        double x = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, x))
            fail(n, key,
                 n.IsScalar() ? log::cat("expected ", what, ", got '", n.Scalar(), "'") : log::cat("expected ", what));
        if (!r.contains(x)) fail(n, key, range_problem(x, r));
        v = x;
    }
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
        fail_at_node(file_, at_or_here(n), where(key), problem);
    }
    YAML::Node at_or_here(const YAML::Node& n) const { return n ? n : node_; }
    std::string where(const std::string& key) const {
        return path_.empty() ? key : (key.empty() ? path_ : path_ + "." + key);
    }

    YAML::Node node_;
    std::string path_;
    const std::string& file_;
    std::set<std::string> used_;
    BrokenRule& broken_;  // shared by the document's readers
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
    void texts(const std::string& key, std::vector<std::string>& v) override {
        out_ << YAML::Key << key << YAML::Value << YAML::Flow << v;
    }
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
    void table(const std::string& key, std::span<double> v, std::size_t cols, const Range&,
               const std::string&) override {
        out_ << YAML::Key << key << YAML::Value << YAML::BeginSeq;
        for (std::size_t i = 0; i + cols <= v.size(); i += cols) {
            out_ << YAML::Flow << YAML::BeginSeq;
            for (std::size_t j = 0; j < cols; ++j) out_ << v[i + j];
            out_ << YAML::EndSeq;
        }
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
    void names(std::vector<std::string>&) override {}
    void list(const std::string& key, std::size_t& count, const Item& item) override {
        out_ << YAML::Key << key << YAML::Value << YAML::BeginSeq;
        for (std::size_t i = 0; i < count; ++i) {
            out_ << YAML::BeginMap;
            item(*this, i);
            out_ << YAML::EndMap;
        }
        out_ << YAML::EndSeq;
    }

private:
    YAML::Emitter& out_;
};

}  // namespace

void read_keys(const YAML::Node& root, const std::string& file, const KeyVisitor::Body& body) {
    BrokenRule broken;
    Reader r(root, "", file, broken);
    r.visit(body, "");
    if (broken) throw InputError(*broken);
}

void read_section(const YAML::Node& root, const std::string& file, const std::string& key,
                  const KeyVisitor::Body& body) {
    BrokenRule broken;
    Reader r(root, "", file, broken);
    r.section(key, body, "");  // the document's other keys are not finished here
    if (broken) throw InputError(*broken);
}

void write_keys(YAML::Emitter& out, const KeyVisitor::Body& body) {
    Writer w(out);
    out << YAML::BeginMap;
    body(w);
    out << YAML::EndMap;
}

}  // namespace dw
