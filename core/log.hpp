#pragma once
// A tiny leveled logger writing one line per event to stderr, safe from several threads.
#include <sstream>
#include <string>
#include <string_view>

namespace dw::log {

enum class Level { trace, debug, info, warn, error, off };

// Throws dw::InputError naming the accepted levels.
Level parse_level(std::string_view text);
void set_level(Level level);
Level level();
// The program name printed before each line ("dw-probe: ...").
void set_program(std::string name);
const std::string& program();

// One line, "program: message", whole even when several threads write at once.
void write(Level level, std::string_view message);
// A progress line: written whatever the level (the tools' --quiet decides), one line at a time.
inline void progress(std::string_view message) { write(Level::info, message); }

template <class... Args>
std::string cat(const Args&... args) {
    std::ostringstream out;
    (out << ... << args);
    return out.str();
}

// The items of a range, printed with `sep` between them ("a, b, c").
template <class Range>
std::string join(const Range& items, std::string_view sep = ", ") {
    std::ostringstream out;
    bool first = true;
    for (const auto& item : items) {
        if (!first) out << sep;
        out << item;
        first = false;
    }
    return out.str();
}
// The alternatives of a range for a message: "a, b or c".
template <class Range>
std::string alternatives(const Range& items) {
    std::ostringstream out;
    const std::size_t n = std::size(items);
    std::size_t i = 0;
    for (const auto& item : items) {
        if (i > 0) out << (i + 1 == n ? " or " : ", ");
        out << item;
        ++i;
    }
    return out.str();
}

template <class... Args>
void trace(const Args&... a) {
    if (level() <= Level::trace) write(Level::trace, cat(a...));
}
template <class... Args>
void debug(const Args&... a) {
    if (level() <= Level::debug) write(Level::debug, cat(a...));
}
template <class... Args>
void info(const Args&... a) {
    if (level() <= Level::info) write(Level::info, cat(a...));
}
template <class... Args>
void warn(const Args&... a) {
    if (level() <= Level::warn) write(Level::warn, cat(a...));
}
template <class... Args>
void error(const Args&... a) {
    if (level() <= Level::error) write(Level::error, cat(a...));
}

}  // namespace dw::log
