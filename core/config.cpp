#include "core/config.hpp"

#include <cctype>
#include <cstring>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "core/files.hpp"
#include "core/log.hpp"
#include "core/text.hpp"

namespace dw {
namespace {
// Walks the document as its readers will see it (aliases expanded), refusing a key given twice in
// one mapping, and more nodes than the text has bytes (+ kNodeSlack): without aliases a node takes
// at least a byte, so only alias expansion gets past it — a 547-byte "billion laughs" walked for
// minutes.
constexpr std::size_t kNodeSlack = 1024;
constexpr int kMaxDepth = 64;  // flow collections ([ and {) open at once; the lab's files nest 5 deep
class KeyWalk {
public:
    KeyWalk(const std::string& name, std::size_t text_bytes) : name_(name), budget_(text_bytes + kNodeSlack) {}
    void walk(const YAML::Node& node) {
        if (++nodes_ > budget_)
            throw InputError(
                log::cat(name_, ": more than ", budget_, " nodes once aliases are expanded (an alias bomb?): refused"));
        if (node.IsSequence()) {
            for (const auto& item : node) walk(item);
            return;
        }
        if (!node.IsMap()) return;
        std::set<std::string> seen;
        for (const auto& kv : node) {
            const std::string key = kv.first.Scalar();
            if (kv.first.IsScalar() && !seen.insert(key).second) {
                throw InputError(log::cat(name_, ":", kv.first.Mark().line + 1, ":", kv.first.Mark().column + 1,
                                          ": key '", quote_bytes(key, kQuotedBytes),
                                          "' appears twice in the same mapping"));
            }
            walk(kv.second);
        }
    }

private:
    const std::string& name_;
    std::size_t budget_, nodes_ = 0;
};
// The indentation of the line that starts at `i`, or nullopt for a blank line.
std::optional<std::size_t> indentation(std::string_view text, std::size_t i) {
    std::size_t k = i;
    while (k < text.size() && text[k] == ' ') ++k;
    if (k >= text.size() || text[k] == '\n' || text[k] == '\r') return std::nullopt;
    return k - i;
}

// Past the lines of a block scalar (`key: |` or `>`) that begins on the line starting at `line_start`:
// its lines (more indented than that line, or blank) are text, not YAML. Returns where the next
// line to scan starts, counting the lines skipped into `line`.
std::size_t skip_block_scalar(std::string_view text, std::size_t line_start, std::size_t from, std::size_t& line) {
    const std::size_t parent = indentation(text, line_start).value_or(0);
    std::size_t i = text.find('\n', from);
    while (i != std::string_view::npos) {
        const auto indent = indentation(text, i + 1);
        if (indent && *indent <= parent) return i;  // the '\n' before the next YAML line
        ++line;
        i = text.find('\n', i + 1);
    }
    return text.size();
}

// yaml-cpp 0.7 (Debian bookworm) loops forever, allocating, on a ',' that begins a token outside
// flow collections (a file that is just ",", or "- 1\n,"): found by tests/test_file_fuzz.cpp. Such
// a ',' is never valid YAML (an indicator cannot begin a plain scalar), so it is refused first.
// Comments, quoted scalars and block scalars (| >, their more-indented lines) are text and skipped.
void refuse_stray_commas(std::string_view text, const std::string& name) {
    int depth = 0;
    std::size_t line = 1, line_start = 0;
    char quote = 0;
    bool boundary = true;  // a token may begin here: a line's start, after "- ", ": ", "? ", or a closing ] }
    auto blank = [&](std::size_t k) { return k >= text.size() || std::isspace(static_cast<unsigned char>(text[k])); };
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '\n') ++line, boundary = true, line_start = i + 1;
        if (quote) {
            if (c == quote) quote = 0;
            continue;
        }
        if (c == '#' && (i == 0 || blank(i - 1))) {
            while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
            continue;
        }
        if (c == ',' && depth == 0 && boundary)
            throw InputError(
                log::cat(name, ":", line, ": a ',' that begins a value outside [ ] or { }: not valid YAML"));
        if ((c == '|' || c == '>') && boundary && depth == 0) {
            i = skip_block_scalar(text, line_start, i, line) - 1;  // the loop's ++i lands on the '\n'
            continue;
        }
        if ((c == '"' || c == '\'') && boundary) quote = c;
        if (c == '[' || c == '{') ++depth;
        if ((c == ']' || c == '}') && depth > 0) --depth;
        if (std::isspace(static_cast<unsigned char>(c))) continue;
        boundary = ((c == '-' || c == ':' || c == '?') && blank(i + 1)) || ((c == ']' || c == '}') && depth == 0);
    }
}
}  // namespace

YAML::Node load_yaml(const std::string& text, const std::string& name, std::string_view language) {
    require_nesting_at_most(text, kMaxDepth, name);  // the parser recurses per level
    refuse_stray_commas(text, name);
    std::vector<YAML::Node> documents;
    try {
        documents = YAML::LoadAll(text);
    } catch (const YAML::ParserException& e) {
        throw InputError(log::cat(name, ":", e.mark.line + 1, ":", e.mark.column + 1, ": not valid ", language, ": ",
                                  quote_bytes(e.msg, kQuotedBytes)));
    }
    if (documents.size() > 1)
        throw InputError(log::cat(name, ":", documents[1].Mark().line + 1,
                                  ": a second document (after '---'): one document per file"));
    const YAML::Node root = documents.empty() ? YAML::Node() : documents.front();
    KeyWalk(name, text.size()).walk(root);
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

namespace {
constexpr std::size_t kKeyPathChars = 40;  // a key path quoted in an error ("classes[0].jet.strength")
}  // namespace

std::string located(const std::string& file, const YAML::Node& node, const std::string& key,
                    const std::string& problem) {
    const std::string what =
        key.empty() ? problem : quote_bytes(key, kKeyPathChars) + ": " + problem;  // "" = the document
    if (node && node.Mark().line >= 0)
        return log::cat(file, ":", node.Mark().line + 1, ":", node.Mark().column + 1, ": ", what);
    return log::cat(file, ": ", what);
}

void fail_at_node(const std::string& file, const YAML::Node& node, const std::string& key, const std::string& problem) {
    throw InputError(located(file, node, key, problem));
}

std::string unknown_key_problem(const std::string& key, const std::set<std::string>& known) {
    return log::cat("unknown key '", quote_bytes(key, kRepeatedKeyBytes),
                    "' (known: ", choices(key, {known.begin(), known.end()}, ", "), ")");
}

}  // namespace dw
