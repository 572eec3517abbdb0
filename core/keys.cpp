#include "core/text.hpp"
#include "core/keys.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
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

// JSON text of a string: quoted, with the escapes RFC 8259 requires.
std::string json_quoted(const std::string& text) {
    std::string out = "\"";
    for (const char ch : text) {
        const auto c = static_cast<unsigned char>(ch);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += ch;
        } else if (c < 0x20) {
            char esc[8];
            std::snprintf(esc, sizeof esc, "\\u%04x", c);
            out += esc;
        } else {
            out += ch;
        }
    }
    return out + "\"";
}

// JSON text of a number: the shortest form that reads back to the same double.
std::string json_number(double v) {
    if (!std::isfinite(v)) throw RuntimeError(log::cat("cannot write ", v, " as a JSON number"));
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

// A plain (unquoted) YAML scalar that JSON reads as itself: a number, true, false or null.
bool json_literal(const std::string& s) {
    if (s == "true" || s == "false" || s == "null") return true;
    const auto digit = [&](std::size_t i) { return i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); };
    if (!digit(0) && !(s[0] == '-' && digit(1))) return false;  // JSON: no '+', '.5', 'inf' or 'nan'
    double x = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), x);
    return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(x);
}

// A parsed document back to JSON text (compact): quoted scalars stay strings ('!' is yaml-cpp's
// tag for a quoted scalar), plain ones that are JSON literals stay literals.
std::string to_json_text(const YAML::Node& n) {
    if (!n || n.IsNull()) return "null";
    if (n.IsScalar()) return n.Tag() != "!" && json_literal(n.Scalar()) ? n.Scalar() : json_quoted(n.Scalar());
    std::string out = n.IsMap() ? "{" : "[";
    bool first = true;
    for (const auto& item : n) {
        if (!first) out += ",";
        first = false;
        out += n.IsMap() ? json_quoted(item.first.Scalar()) + ":" + to_json_text(item.second) : to_json_text(item);
    }
    return out + (n.IsMap() ? "}" : "]");
}

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
                 unknown_hint.empty()
                     ? unknown_key_problem(key, used_)
                     : log::cat("unknown key '", quote_bytes(key, kRepeatedKeyBytes), "': ", unknown_hint,
                                " (expected ", choices(key, {used_.begin(), used_.end()}), ")"));
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
        if (!n.IsSequence() || n.size() != v.size() / cols) fail(n, key, shape);
        rows(n, key, cols, r, shape, v);
    }
    void values(const std::string& key, std::vector<double>& v, const Range& r) override {
        const YAML::Node n = get(key);
        if (!n) return;
        if (!n.IsSequence()) fail(n, key, "expected a list of numbers");
        std::vector<double> out(n.size());
        for (std::size_t i = 0; i < out.size(); ++i) element(n[i], log::cat(key, "[", i, "]"), out[i], r);
        v = std::move(out);
    }
    void matrix(const std::string& key, std::vector<double>& v, std::size_t& rows, std::size_t& cols,
                const Range& r) override {
        const YAML::Node n = get(key);
        if (!n) return;
        if (!n.IsSequence() || n.size() == 0 || !n[0].IsSequence() || n[0].size() == 0)
            fail(n, key, "expected a matrix (a list of rows of numbers)");
        std::vector<double> out(n.size() * n[0].size());
        this->rows(n, key, n[0].size(), r, "rows differ in length", out);
        v = std::move(out);
        rows = n.size();
        cols = n[0].size();
    }
    void verbatim(const std::string& key, std::string& json) override {
        const YAML::Node n = get(key);
        if (n) json = to_json_text(n);
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
    // The rows of the sequence `n` into `out` (row-major), each `cols` numbers in r; a row of
    // another length is `problem` at key[i].
    void rows(const YAML::Node& n, const std::string& key, std::size_t cols, const Range& r, const std::string& problem,
              std::span<double> out) const {
        for (std::size_t i = 0; i < n.size(); ++i) {
            const YAML::Node row = n[i];
            if (!row.IsSequence() || row.size() != cols) fail(row, log::cat(key, "[", i, "]"), problem);
            for (std::size_t j = 0; j < cols; ++j)
                element(row[j], log::cat(key, "[", i, "][", j, "]"), out[i * cols + j], r);
        }
    }
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
                 n.IsScalar() ? log::cat("expected ", what, ", got '", quote_bytes(n.Scalar(), kQuotedBytes), "'")
                              : log::cat("expected ", what));
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
    void values(const std::string& key, std::vector<double>& v, const Range&) override {
        out_ << YAML::Key << key << YAML::Value << YAML::Flow << v;
    }
    void matrix(const std::string& key, std::vector<double>& v, std::size_t& rows, std::size_t& cols,
                const Range& r) override {
        table(key, std::span<double>(v.data(), std::min(v.size(), rows * cols)), cols, r, "");
    }
    void verbatim(const std::string& key, std::string& json) override {
        out_ << YAML::Key << key << YAML::Value << YAML::Load(json);
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

// Writes one JSON object: each visit is one member, indented one space a level.
class JsonWriter final : public KeyVisitor {
public:
    void number(const std::string& key, double& v, const Range&) override { member(key, json_number(v)); }
    void integer(const std::string& key, int& v, const Range&) override { member(key, std::to_string(v)); }
    void flag(const std::string& key, bool& v) override { member(key, v ? "true" : "false"); }
    void text(const std::string& key, std::string& v) override { member(key, json_quoted(v)); }
    void texts(const std::string& key, std::vector<std::string>& v) override {
        member(key, array(v.size(), [&](std::size_t i) { return json_quoted(v[i]); }));
    }
    bool has(const std::string&) override { return true; }
    void choice(const std::string& key, int& v, std::span<const char* const> names, const std::string&,
                const std::string&) override {
        member(key, json_quoted(names[static_cast<std::size_t>(v)]));
    }
    void numbers(const std::string& key, std::span<double> v, const Range&, const std::string&) override {
        member(key, row(v));
    }
    void table(const std::string& key, std::span<double> v, std::size_t cols, const Range&,
               const std::string&) override {
        member(key, array(v.size() / cols, [&](std::size_t i) { return row(v.subspan(i * cols, cols)); }));
    }
    void values(const std::string& key, std::vector<double>& v, const Range&) override { member(key, row(v)); }
    void matrix(const std::string& key, std::vector<double>& v, std::size_t& rows, std::size_t& cols,
                const Range& r) override {
        table(key, std::span<double>(v.data(), std::min(v.size(), rows * cols)), cols, r, "");
    }
    void verbatim(const std::string& key, std::string& json) override { member(key, json); }
    void constant(const std::string& key, const std::string& value) override { member(key, json_quoted(value)); }
    void section(const std::string& key, const Body& body, const std::string&) override {
        open(key, "{");
        body(*this);
        close("}");
    }
    void require(bool, const std::string&, const std::string&) override {}
    void names(std::vector<std::string>&) override {}
    void list(const std::string& key, std::size_t& count, const Item& item) override {
        open(key, "[");
        for (std::size_t i = 0; i < count; ++i) {
            open("", "{");
            item(*this, i);
            close("}");
        }
        close("]");
    }

    std::string document(const Body& body) {
        out_ = "{";
        firsts_ = {true};
        body(*this);
        close("}");
        return out_ + "\n";
    }

private:
    // "[a, b, c]" of n items, item(i) the text of each.
    template <class Item>
    static std::string array(std::size_t n, const Item& item) {
        std::string a = "[";
        for (std::size_t i = 0; i < n; ++i) a += (i ? ", " : "") + item(i);
        return a + "]";
    }
    static std::string row(std::span<const double> v) {
        return array(v.size(), [&](std::size_t i) { return json_number(v[i]); });
    }
    // A new member (or array element, when key is empty) on its own line.
    void start(const std::string& key) {
        if (!firsts_.back()) out_ += ",";
        firsts_.back() = false;
        out_ += "\n" + std::string(firsts_.size(), ' ');
        if (!key.empty()) out_ += json_quoted(key) + ": ";
    }
    void member(const std::string& key, const std::string& value) {
        start(key);
        out_ += value;
    }
    void open(const std::string& key, const char* bracket) {
        start(key);
        out_ += bracket;
        firsts_.push_back(true);
    }
    void close(const char* bracket) {
        const bool empty = firsts_.back();
        firsts_.pop_back();
        if (!empty) out_ += "\n" + std::string(firsts_.size(), ' ');
        out_ += bracket;
    }

    std::string out_;
    std::vector<bool> firsts_;  // per open object or array: nothing written in it yet
};

}  // namespace

std::string write_json_keys(const KeyVisitor::Body& body) { return JsonWriter().document(body); }

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

namespace {

// Collects every value visited (KeyValues).
class ValueCollector final : public KeyVisitor {
public:
    explicit ValueCollector(KeyValues& out) : out_(out) {}
    void number(const std::string&, double& v, const Range&) override { add(v); }
    void integer(const std::string&, int& v, const Range&) override { add(v); }
    void flag(const std::string&, bool& v) override { add(v ? 1 : 0); }
    void text(const std::string&, std::string& v) override { out_.texts.push_back(v); }
    void texts(const std::string&, std::vector<std::string>& v) override { add_words(v); }
    bool has(const std::string&) override { return true; }
    void choice(const std::string&, int& v, std::span<const char* const>, const std::string&,
                const std::string&) override {
        add(v);
    }
    void numbers(const std::string&, std::span<double> v, const Range&, const std::string&) override { add_all(v); }
    void table(const std::string&, std::span<double> v, std::size_t, const Range&, const std::string&) override {
        add_all(v);
    }
    void values(const std::string&, std::vector<double>& v, const Range&) override { add_all(v); }
    void matrix(const std::string&, std::vector<double>& v, std::size_t& rows, std::size_t& cols,
                const Range&) override {
        add(static_cast<double>(rows));
        add(static_cast<double>(cols));
        add_all(v);
    }
    void verbatim(const std::string&, std::string& json) override { out_.texts.push_back(json); }
    void constant(const std::string&, const std::string&) override {}
    void section(const std::string&, const Body& body, const std::string&) override { body(*this); }
    void names(std::vector<std::string>& v) override { add_words(v); }
    void list(const std::string&, std::size_t& count, const Item& item) override {
        add(static_cast<double>(count));
        for (std::size_t i = 0; i < count; ++i) item(*this, i);
    }
    void require(bool, const std::string&, const std::string&) override {}

private:
    void add(double v) { out_.numbers.push_back(std::bit_cast<std::uint64_t>(v)); }
    void add_all(std::span<const double> v) {
        add(static_cast<double>(v.size()));
        for (double x : v) add(x);
    }
    void add_words(const std::vector<std::string>& v) {
        add(static_cast<double>(v.size()));
        out_.texts.insert(out_.texts.end(), v.begin(), v.end());
    }
    KeyValues& out_;
};

}  // namespace

KeyValues key_values(const KeyVisitor::Body& body) {
    KeyValues out;
    ValueCollector c(out);
    body(c);
    return out;
}

}  // namespace dw
