// dw-mocap-bridge: OptiTrack NatNet (or its simulation) at the camera rate onto DDS.
#include <array>
#include <sstream>

#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "core/shutdown.hpp"
#include "dds/endpoint.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "mocap_bridge/hostile_cli.hpp"
#include "mocap_bridge/bridge.hpp"
#include "mocap_bridge/px4_source.hpp"
#include "mocap_bridge/sim_source.hpp"
#include "swarm_planner/px4_odometry.hpp"
#include "physics/config.hpp"

namespace {

enum class Source { natnet, sim, px4 };
constexpr std::array<std::pair<const char*, Source>, 3> kSources{
    {{"natnet", Source::natnet}, {"sim", Source::sim}, {"px4", Source::px4}}};

// --feed-px4's settings: the file must give the feed to the bridge, so the planner does not feed it too.
dw::planner::Px4Options feed_options(const std::string& file, const std::vector<std::string>& vehicles) {
    auto o = dw::planner::load_px4_options(file, vehicles);
    if (o.odometry != dw::planner::OdometryBy::bridge)
        throw dw::InputError(dw::log::cat("--feed-px4: ", file,
                                          " says odometry: ", dw::name_of(dw::planner::kOdometryByNames, o.odometry),
                                          " (expected bridge: one feed per PX4, the planner reads the same file)"));
    return o;
}

// The NatNet path (Motive, or the simulated vehicles behind an emulated Motive).
struct NatNetArgs {
    std::string axes = "x,z,-y", mode = "compensated", sim_vehicles = "v1,v2,v3", sim_fault;
    std::vector<std::string> name_map;
    dw::natnet::ClientOptions client;
    double sim_rate = 180.0;
    dw::natnet::Hostility sim_hostile;            // a hostile Motive behind the sim source (tests, issue 70)
    std::optional<dw::planner::Px4Options> feed;  // --feed-px4: the motion capture into each PX4's estimator
};

dw::natnet::BridgeOptions bridge_options(const NatNetArgs& a) {
    dw::natnet::BridgeOptions bo;
    bo.axes = dw::natnet::AxisMap::parse(a.axes);
    if (a.mode == "receive") bo.mode = dw::msg::MOCAP_STAMP_RECEIVE;
    else if (a.mode == "compensated") bo.mode = dw::msg::MOCAP_STAMP_COMPENSATED;
    else if (a.mode == "clock_sync") bo.mode = dw::msg::MOCAP_STAMP_CLOCK_SYNC;
    else throw dw::InputError("--timestamps: '" + a.mode + "' (expected receive, compensated or clock_sync)");
    for (const auto& n : a.name_map) {
        const auto eq = n.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == n.size())
            throw dw::InputError("--name '" + n + "': expected RIGIDBODY=VEHICLE");
        bo.names[n.substr(0, eq)] = n.substr(eq + 1);
    }
    return bo;
}

int bridge_natnet(dw::dds::ProcessCli& cli, NatNetArgs a, bool simulated_source) {
    const dw::natnet::BridgeOptions bo = bridge_options(a);
    std::optional<dw::natnet::SimFault> fault;
    if (!a.sim_fault.empty()) fault = dw::natnet::parse_sim_fault(a.sim_fault);
    dw::dds::Participant participant(cli.dds(), "mocap_bridge", cli.clock());
    dw::dds::Heartbeat heartbeat(participant);
    std::unique_ptr<dw::natnet::SimSource> simulated;
    if (simulated_source) {
        std::vector<std::string> names{dw::flight::kSufferer};
        std::stringstream in(a.sim_vehicles);
        for (std::string v; std::getline(in, v, ',');) names.push_back(v);
        simulated = std::make_unique<dw::natnet::SimSource>(participant, names, a.sim_rate, fault, a.sim_hostile);
        a.client.server_ip = "127.0.0.1";
        a.client.local_ip = "127.0.0.1";
        a.client.command_port = simulated->port();
        dw::log::info("simulated motion capture: emulated NatNet server on 127.0.0.1:", a.client.command_port);
    }
    dw::natnet::NatNetClient natnet(a.client);
    const auto server = natnet.connect();
    const auto models = natnet.request_modeldef();
    dw::log::info("NatNet ", server.natnet.major, ".", server.natnet.minor, " from ", server.app_name, ": ",
                  models.rigid_bodies.size(), " rigid bodies");
    dw::natnet::FrameConverter converter(bo, server, models);
    dw::dds::Writer<dw::msg::MocapFrame> frames(participant, dw::dds::topics::mocap_frame);
    dw::dds::Writer<dw::msg::VehicleState> states(participant, dw::dds::topics::vehicle_state);
    std::unique_ptr<dw::planner::Px4OdometryFeed> feed;
    if (a.feed) feed = std::make_unique<dw::planner::Px4OdometryFeed>(participant, *a.feed, false);
    heartbeat.set_state(dw::msg::PROC_RUNNING);
    std::uint64_t n = 0;
    while (!dw::Shutdown::instance().requested()) {
        auto r = natnet.next_frame(100);
        if (!r) continue;
        bool refused = false;
        auto out = converter.convert(r->frame, r->receive_wall_ns, &refused);
        if (refused) continue;
        frames.write(out.frame);
        for (auto& s : out.states) {
            states.write(s);
            if (feed) feed->on_state(s);
        }
        ++n;
    }
    dw::log::info("bridged ", n, " frames; ", converter.dropped(), " dropped by the network or server; ",
                  natnet.malformed(), " malformed packets skipped; ", converter.implausible(),
                  " non-finite or implausible bodies and frames refused; ", converter.undefined(),
                  " bodies of no model definition left out of vehicles/state");
    return 0;
}

// The PX4-estimate path: no motion capture, each PX4's own estimate (mocap_bridge/px4_source.hpp).
int bridge_px4(dw::dds::ProcessCli& cli, dw::natnet::Px4SourceOptions o) {
    dw::dds::Participant participant(cli.dds(), "mocap_bridge", cli.clock());
    dw::dds::Heartbeat heartbeat(participant);
    dw::natnet::Px4PoseSource source(participant, std::move(o));
    dw::dds::Writer<dw::msg::MocapFrame> frames(participant, dw::dds::topics::mocap_frame);
    dw::dds::Writer<dw::msg::VehicleState> states(participant, dw::dds::topics::vehicle_state);
    heartbeat.set_state(dw::msg::PROC_RUNNING);
    const auto period = std::chrono::duration<double>(1.0 / source.options().rate_hz);
    while (!dw::Shutdown::instance().wait_for(std::chrono::duration_cast<std::chrono::nanoseconds>(period))) {
        auto out = source.frame(participant.clock().now_ns());
        frames.write(out.frame);
        for (auto& s : out.states) states.write(s);
    }
    dw::log::info("published PX4's estimates: ", source.received(), " received, ", source.rejected(),
                  " not used (not a finite pose in NED)");
    return 0;
}

// dw-mocap-bridge's one command: the motion capture (or PX4's estimate) onto DDS.
struct BridgeCommand final : dw::cli::Command {
    explicit BridgeCommand(dw::dds::ProcessCli& c) : cli(c) {}
    dw::dds::ProcessCli& cli;
    std::string source = "natnet", px4_file, physics_file, feed_file;
    std::vector<std::string> px4_vehicles{"v1"};
    NatNetArgs a;
    bool sim = false;
    dw::natnet::Px4SourceOptions po;

    CLI::App* add(CLI::App& app) override {
        app.add_option("--source", source,
                       "natnet (Motive), sim (simulated vehicles through an emulated NatNet server), or px4 (no motion "
                       "capture: each PX4's own estimate, fmu/out/vehicle_odometry)");
        app.add_flag("--sim", sim, "same as --source sim");
        app.add_option("--server", a.client.server_ip, "Motive host (natnet)");
        app.add_option("--command-port", a.client.command_port, "NatNet command port (default 1510)")
            ->check(dw::cli::in(dw::natnet::kPortRange));
        app.add_option("--local-ip", a.client.local_ip, "this host's address towards Motive");
        app.add_option("--axes", a.axes, "NED axes as Motive axes: default x,z,-y (Y up)");
        app.add_option("--name", a.name_map, "RIGIDBODY=VEHICLE (repeatable)");
        app.add_option("--timestamps", a.mode, "receive, compensated (default) or clock_sync");
        app.add_option("--sim-vehicles", a.sim_vehicles, "sim: the neighbours' names (they follow vehicles/setpoint)");
        app.add_option("--sim-fault", a.sim_fault,
                       "sim: KIND:VEHICLE:AFTER_S — the vehicle stops following its setpoints (stuck) or mocap "
                       "reports it 10 m away (jump), AFTER_S after its first setpoint (fault tests)");
        app.add_option("--sim-rate", a.sim_rate, "sim: camera rate [Hz]")->check(dw::cli::in({1, 1000, "Hz"}));
        dw::natnet::add_hostility_options(app, a.sim_hostile, "sim-");
        app.add_option("--px4-vehicles", px4_vehicles,
                       "px4 and --feed-px4: the vehicles, comma-separated (the plan's names)")
            ->delimiter(',');
        app.add_option("--px4", px4_file,
                       "px4: the planner's PX4 settings file (each vehicle's namespace, origin and heading; default: "
                       "namespace = name, origin 0, heading 0)");
        app.add_option("--physics", physics_file,
                       "px4: physics configuration (the stand's height: where the sufferer is)");
        app.add_option(
            "--feed-px4", feed_file,
            "natnet/sim: also feed each tracked vehicle's pose to its PX4's estimator (vehicle_visual_odometry), "
            "whenever it is tracked, per this PX4 settings file (it must say odometry: bridge); vehicles from "
            "--px4-vehicles");
        app.add_option("--px4-rate", po.rate_hz, "px4: frames published per second")
            ->check(dw::cli::in(dw::natnet::kEstimateRateRange));
        return &app;
    }
    int run() override {
        CLI::App& app = cli.app();
        const Source kind =
            sim ? Source::sim : dw::parse_entry(kSources, source, "source", "--source (replay: dw-recorder replay)");
        if (kind != Source::px4) {
            if (app.count("--feed-px4") > 0) a.feed = feed_options(feed_file, px4_vehicles);
            return bridge_natnet(cli, std::move(a), kind == Source::sim);
        }
        po.px4 = app.count("--px4") == 0 ? dw::planner::default_px4_options(px4_vehicles)
                                         : dw::planner::load_px4_options(px4_file, px4_vehicles);
        const auto physics = dw::physics::physics_or_defaults(physics_file);
        po.sufferer = dw::physics::sufferer_on_stand(physics.stand);
        return bridge_px4(cli, std::move(po));
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli(
        "dw-mocap-bridge: OptiTrack NatNet motion capture onto DDS (180 Hz), its simulation, or PX4's own estimate");
    BridgeCommand bridge(cli);
    return dw::cli::run_commands(cli.app(), {&bridge}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-mocap-bridge", [&] { return run(argc, argv); });
}
