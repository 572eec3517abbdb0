#include "core/command.hpp"

#include <stdexcept>
#include <utility>
#include <vector>

namespace dw::cli {

int run_commands(CLI::App& app, const std::vector<Command*>& commands, const std::function<void()>& parse) {
    std::vector<std::pair<CLI::App*, Command*>> added;
    for (auto* c : commands) added.emplace_back(c->add(app), c);
    parse();
    Command* main = nullptr;
    for (const auto& [where, c] : added) {
        if (where == &app) main = c;
        else if (where->parsed()) return c->run();
    }
    if (!main) throw std::logic_error(app.get_name() + ": no command chosen and no main command");
    return main->run();
}

}  // namespace dw::cli
