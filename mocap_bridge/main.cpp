// dw-mocap-bridge: OptiTrack NatNet (or its simulation) at the camera rate onto DDS.
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/endpoint.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "mocap_bridge/bridge.hpp"
#include "mocap_bridge/sim_source.hpp"

namespace {

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-mocap-bridge: OptiTrack NatNet motion capture onto DDS (180 Hz), or its simulation");
    CLI::App& app = cli.app();
    std::string source = "natnet", axes = "x,z,-y", mode = "compensated", sim_vehicles = "v1,v2,v3";
    std::vector<std::string> name_map;
    dw::natnet::ClientOptions client;
    bool sim = false;
    double sim_rate = 180.0;
    app.add_option("--source", source,
                   "natnet (Motive), or sim (simulated vehicles through an emulated NatNet server)");
    app.add_flag("--sim", sim, "same as --source sim");
    app.add_option("--server", client.server_ip, "Motive host (natnet)");
    app.add_option("--command-port", client.command_port, "NatNet command port (default 1510)")
        ->check(dw::cli::in(dw::natnet::kPortRange));
    app.add_option("--local-ip", client.local_ip, "this host's address towards Motive");
    app.add_option("--axes", axes, "NED axes as Motive axes: default x,z,-y (Y up)");
    app.add_option("--name", name_map, "RIGIDBODY=VEHICLE (repeatable)");
    app.add_option("--timestamps", mode, "receive, compensated (default) or clock_sync");
    app.add_option("--sim-vehicles", sim_vehicles, "sim: the neighbours' names (they follow vehicles/setpoint)");
    std::string sim_fault;
    app.add_option("--sim-fault", sim_fault,
                   "sim: KIND:VEHICLE:AFTER_S — the vehicle stops following its setpoints (stuck) or mocap "
                   "reports it 10 m away (jump), AFTER_S after its first setpoint (fault tests)");
    app.add_option("--sim-rate", sim_rate, "sim: camera rate [Hz]")->check(dw::cli::in({1, 1000, "Hz"}));
    cli.parse(argc, argv);
    if (sim) source = "sim";
    if (source != "natnet" && source != "sim")
        throw dw::InputError("--source: '" + source + "' (expected natnet or sim; replay: dw-recorder replay)");

    dw::natnet::BridgeOptions bo;
    bo.axes = dw::natnet::AxisMap::parse(axes);
    if (mode == "receive") bo.mode = dw::msg::MOCAP_STAMP_RECEIVE;
    else if (mode == "compensated") bo.mode = dw::msg::MOCAP_STAMP_COMPENSATED;
    else if (mode == "clock_sync") bo.mode = dw::msg::MOCAP_STAMP_CLOCK_SYNC;
    else throw dw::InputError("--timestamps: '" + mode + "' (expected receive, compensated or clock_sync)");
    for (const auto& n : name_map) {
        const auto eq = n.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == n.size())
            throw dw::InputError("--name '" + n + "': expected RIGIDBODY=VEHICLE");
        bo.names[n.substr(0, eq)] = n.substr(eq + 1);
    }

    std::optional<dw::natnet::SimFault> fault;
    if (!sim_fault.empty()) fault = dw::natnet::parse_sim_fault(sim_fault);
    dw::dds::Participant participant(cli.dds(), "mocap_bridge", cli.clock());
    dw::dds::Heartbeat heartbeat(participant);
    std::unique_ptr<dw::natnet::SimSource> simulated;
    if (source == "sim") {
        std::vector<std::string> names{dw::flight::kSufferer};
        std::stringstream in(sim_vehicles);
        for (std::string v; std::getline(in, v, ',');) names.push_back(v);
        simulated = std::make_unique<dw::natnet::SimSource>(participant, names, sim_rate, fault);
        client.server_ip = "127.0.0.1";
        client.local_ip = "127.0.0.1";
        client.command_port = simulated->port();
        dw::log::info("simulated motion capture: emulated NatNet server on 127.0.0.1:", client.command_port);
    }
    dw::natnet::NatNetClient natnet(client);
    const auto server = natnet.connect();
    const auto models = natnet.request_modeldef();
    dw::log::info("NatNet ", server.natnet.major, ".", server.natnet.minor, " from ", server.app_name, ": ",
                  models.rigid_bodies.size(), " rigid bodies");
    dw::natnet::FrameConverter converter(bo, server, models);
    dw::dds::Writer<dw::msg::MocapFrame> frames(participant, dw::dds::topics::mocap_frame);
    dw::dds::Writer<dw::msg::VehicleState> states(participant, dw::dds::topics::vehicle_state);
    heartbeat.set_state(dw::msg::PROC_RUNNING);
    std::uint64_t n = 0;
    while (!dw::Shutdown::instance().requested()) {
        auto r = natnet.next_frame(100);
        if (!r) continue;
        auto out = converter.convert(r->frame, r->receive_wall_ns);
        frames.write(out.frame);
        for (auto& s : out.states) states.write(s);
        ++n;
    }
    dw::log::info("bridged ", n, " frames; ", converter.dropped(), " dropped by the network or server; ",
                  natnet.malformed(), " malformed packets skipped");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-mocap-bridge", [&] { return run(argc, argv); });
}
