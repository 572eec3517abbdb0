#include "core/log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>

#include "core/errors.hpp"
#include "core/names.hpp"

namespace dw::log {
namespace {
std::atomic<Level> g_level{Level::info};
std::string g_program = "dw";
std::mutex g_mutex;

constexpr std::string_view kNames[] = {"trace", "debug", "info", "warn", "error", "off"};
}  // namespace

Level parse_level(std::string_view text) { return parse_name<Level>(kNames, text, "log level"); }

void set_level(Level l) { g_level = l; }
Level level() { return g_level; }
void set_program(std::string name) { g_program = std::move(name); }
const std::string& program() { return g_program; }

void write(Level l, std::string_view message) {
    std::lock_guard lock(g_mutex);
    std::fprintf(stderr, "%s: %s%s%.*s\n", g_program.c_str(),
                 l == Level::info ? "" : kNames[static_cast<int>(l)].data(), l == Level::info ? "" : ": ",
                 static_cast<int>(message.size()), message.data());
}

}  // namespace dw::log
