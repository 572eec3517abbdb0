#pragma once
// A configuration's keys declared once and both read and written from that declaration. A struct's
// keys are listed in one function that visits them with a KeyVisitor; reading YAML (strictly:
// every key must be visited, numbers range-checked, errors "file:line:col: path.key: problem")
// and writing YAML are two visitors of that one list, so a key cannot be parsed and forgotten by
// the writer, or written under another name.
#include <yaml-cpp/yaml.h>

#include <compare>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/numbers.hpp"

namespace dw {

class KeyVisitor {
public:
    using Body = std::function<void(KeyVisitor&)>;
    virtual ~KeyVisitor() = default;

    virtual void number(const std::string& key, double& v, const Range& r) = 0;
    virtual void integer(const std::string& key, int& v, const Range& r) = 0;
    virtual void flag(const std::string& key, bool& v) = 0;
    // Free text: a name, a namespace.
    virtual void text(const std::string& key, std::string& v) = 0;
    // A list of free-text words: addresses, names.
    virtual void texts(const std::string& key, std::vector<std::string>& v) = 0;
    // Whether the mapping holds `key` (always, when writing): for keys that must be given.
    virtual bool has(const std::string& key) = 0;
    // One of `names` (v is its index): "unknown <what> 'x' (expected a, b or c<note>)".
    virtual void choice(const std::string& key, int& v, std::span<const char* const> names, const std::string& what,
                        const std::string& note = "") = 0;
    // A fixed-length list of numbers, each in r; `shape` is the message when it is not ("expected [n, e, d] in metres").
    virtual void numbers(const std::string& key, std::span<double> v, const Range& r, const std::string& shape) = 0;
    // A table of numbers (row-major in `v`, `cols` per row), each in r; `shape` is the message when
    // it is not that shape ("expected 6 rows of 8 numbers").
    virtual void table(const std::string& key, std::span<double> v, std::size_t cols, const Range& r,
                       const std::string& shape) = 0;
    // A list of numbers of any length, each in r (when reading: as long as the file's).
    virtual void values(const std::string& key, std::vector<double>& v, const Range& r) = 0;
    // A matrix: a non-empty list of rows of one non-zero length, each number in r; `v` row-major,
    // `rows` x `cols` (when reading: the file's shape; rows of different lengths are an error).
    virtual void matrix(const std::string& key, std::vector<double>& v, std::size_t& rows, std::size_t& cols,
                        const Range& r) = 0;
    // A document kept as it is, as JSON text, without reading its keys (a file's free metadata).
    virtual void verbatim(const std::string& key, std::string& json) = 0;
    // A key that, when given, must say exactly `value` (a format tag); always written.
    virtual void constant(const std::string& key, const std::string& value) = 0;
    // The mapping under `key`; a key in it that `body` does not visit is "unknown key 'x'" and its
    // known keys, or, given `unknown_hint`, "unknown key 'x': <hint> (expected <the keys visited>)".
    virtual void section(const std::string& key, const Body& body, const std::string& unknown_hint = "") = 0;
    // The keys of this mapping when they are names the user chose (hosts, variables): when reading,
    // `v` becomes the file's keys in order (each must then be visited); when writing, `v` is kept.
    virtual void names(std::vector<std::string>& v) = 0;
    // A list of mappings under `key`, `count` long (when reading: the file's), each item visited by
    // `item` with its index (errors say key[i].field).
    using Item = std::function<void(KeyVisitor&, std::size_t)>;
    virtual void list(const std::string& key, std::size_t& count, const Item& item) = 0;
    // A rule between values already visited: when reading, !ok is an error at `key`.
    virtual void require(bool ok, const std::string& key, const std::string& problem) = 0;

    // A format tag that must be given and say exactly `value`.
    void required_constant(const std::string& key, const std::string& value) {
        require(has(key), key, "expected " + value);
        constant(key, value);
    }

    // choice() of an enum whose values are 0..N-1 in the order of `names`.
    template <class E>
    void enumeration(const std::string& key, E& v, std::span<const char* const> names, const std::string& what,
                     const std::string& note = "") {
        int index = static_cast<int>(v);
        choice(key, index, names, what, note);
        v = static_cast<E>(index);
    }
};

// Reads the mapping `root` (or an empty document) of `file` through `body`; throws dw::InputError
// at the first problem.
void read_keys(const YAML::Node& root, const std::string& file, const KeyVisitor::Body& body);
// Reads only the mapping under `key` of the document `root` through `body` (strictly), leaving
// the document's other keys to other readers; nothing when `key` is absent.
void read_section(const YAML::Node& root, const std::string& file, const std::string& key,
                  const KeyVisitor::Body& body);
// Writes what `body` visits as one YAML mapping.
void write_keys(YAML::Emitter& out, const KeyVisitor::Body& body);

// The same declaration as JSON. JSON is YAML's flow style, so a JSON document is read by the same
// strict reader: read_keys(load_yaml(text, file, "JSON"), file, body) (errors "file:line:col: key:
// problem"; a syntax error says "not valid JSON"). Written as one JSON object, indented one space a
// level; a non-finite number cannot be written (dw::RuntimeError).
std::string write_json_keys(const KeyVisitor::Body& body);

// Every value `body` visits, exactly, in its order (numbers by their bits; the lengths of lists
// with them, so that two declarations' values cannot run together): a key for a cache of what a
// configuration computes, without writing it as text. Equal configurations give equal keys.
struct KeyValues {
    std::vector<std::uint64_t> numbers;
    std::vector<std::string> texts;
    auto operator<=>(const KeyValues&) const = default;
};
KeyValues key_values(const KeyVisitor::Body& body);

}  // namespace dw
