// dw-viewer: the lab live in a browser (its own page) and in Foxglove or Lichtblick (the Foxglove
// WebSocket protocol), on one port. Reads every lab topic; publishes nothing.
#include <chrono>
#include <iostream>

#include "core/command.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/process_cli.hpp"
#include "viewer/hub.hpp"
#include "viewer/server.hpp"

namespace {

constexpr std::chrono::seconds kStatusEvery{10};

// dw-viewer's one command: serve the lab live until stopped.
struct ViewerCommand final : dw::cli::Command {
    explicit ViewerCommand(const dw::dds::ProcessCli& c) : cli(c) {}
    const dw::dds::ProcessCli& cli;
    dw::viewer::ServerOptions o;

    CLI::App* add(CLI::App& app) override {
        app.add_option("--bind", o.bind,
                       "address to listen on (default 127.0.0.1: this machine only; 0.0.0.0: "
                       "every interface, for laptops on the lab network)");
        app.add_option("--port", o.port, "TCP port (0: any free one)")->check(dw::cli::in(dw::kPortRange));
        return &app;
    }
    int run() override {
        dw::dds::Participant participant(cli.dds(), "viewer", cli.clock());
        dw::viewer::Hub hub(participant);
        dw::viewer::Server server(hub, o);
        const auto ws = "ws://" + server.url().substr(7);
        // The address first and alone on stdout: dw-lab and the tests read it.
        std::cout << "viewer at " << server.url() << std::endl;
        dw::log::info("open ", server.url(),
                      " in a browser; in Foxglove or Lichtblick: Open connection, Foxglove "
                      "WebSocket, ",
                      ws.substr(0, ws.size() - 1));
        const auto say = [&] {
            const auto s = server.stats();
            dw::log::info(s.clients, " client(s), ", hub.received(), " samples read, ", s.frames, " frames sent, ",
                          s.dropped, " dropped for slow clients");
        };
        auto next = std::chrono::steady_clock::now() + kStatusEvery;
        while (!dw::Shutdown::instance().wait_for(std::chrono::milliseconds(200))) {
            if (std::chrono::steady_clock::now() < next) continue;
            next += kStatusEvery;
            say();
        }
        say();
        return 0;
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli(
        "dw-viewer: the lab live — a page for any browser and the Foxglove WebSocket protocol for Foxglove or "
        "Lichtblick, on one port; read-only");
    ViewerCommand viewer(cli);
    return dw::cli::run_commands(cli.app(), {&viewer}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-viewer", [&] { return run(argc, argv); });
}
