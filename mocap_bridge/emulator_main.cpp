// dw-natnet-emulator: a NatNet server on loopback sending real-format packets (a test tool).
#include <iostream>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "mocap_bridge/emulator.hpp"
#include "mocap_bridge/hostile_cli.hpp"

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-natnet-emulator", [&] {
        CLI::App app{"dw-natnet-emulator: an OptiTrack NatNet server emulator on loopback (real packet formats)"};
        dw::cli::BaseOptions base;
        dw::cli::configure(app, base);
        dw::natnet::EmulatorOptions o;
        std::string version = "4.1";
        double lose_body = -1, lose_at = 0, lose_for = 0;
        app.add_option("--ip", o.ip, "address to listen on (tests: 127.0.0.1)");
        app.add_option("--port", o.port, "command port (default 1510; 0 = any)")
            ->check(dw::cli::in(dw::natnet::kPortRange));
        app.add_option("--version", version, "NatNet bitstream: 3.0, 3.1, 4.0 or 4.1");
        app.add_option("--rate", o.rate_hz, "frames per second")->check(dw::cli::in({1, 2000, "Hz"}));
        app.add_option("--drop", o.drop_probability, "probability that a frame is not sent")
            ->check(dw::cli::in({0, 1}));
        app.add_option("--lose-body", lose_body, "index of a body that loses tracking (-1 = none)")
            ->check(dw::cli::in({-1, 1000}));
        app.add_option("--lose-at", lose_at, "... at this time [s]")->check(dw::cli::in(dw::kTimeoutRange));
        app.add_option("--lose-for", lose_for, "... for this long [s]")->check(dw::cli::in(dw::kTimeoutRange));
        app.add_option("--seed", o.seed, "random seed (drops)")->check(dw::cli::in(dw::kSeedRange));
        dw::natnet::add_hostility_options(app, o.hostile, "");
        dw::cli::parse(app, argc, argv);
        dw::log::set_level(dw::log::parse_level(base.log_level));
        if (version == "3.0") o.version = {3, 0};
        else if (version == "3.1") o.version = {3, 1};
        else if (version == "4.0") o.version = {4, 0};
        else if (version == "4.1") o.version = {4, 1};
        else throw dw::InputError("--version: '" + version + "' (expected 3.0, 3.1, 4.0 or 4.1)");
        if (lose_body >= 0) o.losses.push_back({static_cast<int>(lose_body), lose_at, lose_for});
        dw::natnet::NatNetEmulator emulator(o);
        dw::log::info("NatNet ", version, " server on ", o.ip, ":", emulator.port(), ", ", o.rate_hz, " Hz");
        while (!dw::Shutdown::instance().wait_for(std::chrono::seconds(1))) {}
        dw::log::info("sent ", emulator.frames_sent(), " frames");
        return 0;
    });
}
