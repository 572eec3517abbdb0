#include "core/config.hpp"

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
}  // namespace

YAML::Node load_yaml(const std::string& text, const std::string& name, std::string_view language) {
    require_nesting_at_most(text, kMaxDepth, name);  // the parser recurses per level
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
