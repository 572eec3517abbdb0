// dw-px4-sim: simulated PX4 vehicles on the lab's domain (px4_sim/simulated_px4.hpp) — PX4's
// uXRCE-DDS topics and Commander rules, each vehicle also playing its motion capture — so that
// `dw-planner run --vehicles px4` can be tried on one machine. Not a flight simulator: each
// vehicle closes on its setpoint at a fixed rate.
#include <optional>
#include <iostream>

#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "mocap_bridge/emulator.hpp"
#include "physics/config.hpp"
#include "physics/wrench_model.hpp"
#include "px4_sim/simulated_px4.hpp"

namespace {

constexpr dw::Range kLoseAfterRange{0, 3600, "s"};
constexpr dw::Range kOriginAboveFloorRange{-100, 100, "m"};
constexpr dw::Range kTimeJumpEveryRange{0, 3600, "s"};
constexpr double kParkedNorth_m = -1.5, kParkedEast0_m = -2.0,
                 kParkedSpacing_m = 1.0;  // in a row at the fence's south side

// The vehicles' motion capture as an emulated Motive (NatNet) on 127.0.0.1:port: the sufferer on
// the stand and each simulated PX4 where it is, for the real dw-mocap-bridge to read.
std::unique_ptr<dw::natnet::NatNetEmulator> motion_capture(
    std::uint16_t port, double stand_height_m, const std::vector<std::string>& names,
    const std::vector<std::unique_ptr<dw::px4sim::SimulatedPx4>>& sims) {
    dw::natnet::EmulatorOptions o;
    o.port = port;
    o.names = {dw::flight::kSufferer};
    o.names.insert(o.names.end(), names.begin(), names.end());
    o.motion = [stand_height_m, &sims](int body, double) {
        dw::natnet::BodyPose p;
        const dw::physics::Vec3 x = body == 0 ? dw::physics::sufferer_on_stand({.height_m = stand_height_m})
                                              : sims.at(static_cast<std::size_t>(body - 1))->lab_position();
        p.ned = {x.x(), x.y(), x.z()};
        return p;
    };
    return std::make_unique<dw::natnet::NatNetEmulator>(o);
}

// What the simulated PX4s are told to do wrong (0 s: never), and where their origin is (unset: as
// PX4 does it, SimulatedPx4Options).
struct Faults {
    std::string refuse_arm;
    double lose_after = 0, kill_after = 0, low_battery_after = 0;
    std::optional<double> origin_above_floor;
    bool land_detector_fooled = false;
    double time_jump_every = dw::px4sim::kTimeJumpEvery_s;
};

std::vector<std::unique_ptr<dw::px4sim::SimulatedPx4>> start_vehicles(dw::dds::Participant& lab,
                                                                      dw::dds::ProcessCli& cli,
                                                                      const dw::planner::Px4Options& options,
                                                                      const Faults& faults, bool publish_state,
                                                                      dw::px4sim::PositionSource source) {
    std::vector<std::unique_ptr<dw::px4sim::SimulatedPx4>> sims;
    for (std::size_t i = 0; i < options.vehicles.size(); ++i) {
        const auto& v = options.vehicles[i];
        dw::px4sim::SimulatedPx4Options o;
        o.version = options.version;
        o.ns = v.ns;
        o.system_id = v.system_id;
        o.vehicle = v.name;
        o.frame = dw::planner::local_frame(v);
        o.parked = dw::physics::Vec3(kParkedNorth_m, kParkedEast0_m + kParkedSpacing_m * static_cast<double>(i), 0);
        o.refuse_arm = faults.refuse_arm;
        o.publish_state = publish_state;
        o.position_source = source;
        if (faults.lose_after > 0) o.lose_offboard_after_s = faults.lose_after;
        if (faults.kill_after > 0) o.kill_after_s = faults.kill_after;
        if (faults.low_battery_after > 0) o.low_battery_after_s = faults.low_battery_after;
        o.origin_above_floor_m = faults.origin_above_floor;
        o.land_detector_fooled = faults.land_detector_fooled;
        o.time_jump_every_s = faults.time_jump_every;
        sims.push_back(std::make_unique<dw::px4sim::SimulatedPx4>(lab, cli.dds(), o));
        std::cout << v.name << ": simulated PX4 " << dw::dds::px4_version(options.version).name << ", MAV_SYS_ID "
                  << v.system_id << ", topics " << dw::dds::px4_topic(v.ns, "in", "...") << std::endl;
    }
    return sims;
}

// What PX4 does wrong or differently, each option into its field of `f`; the origin's option is
// read after parsing (unset: as PX4 does it).
void add_fault_options(CLI::App& app, Faults& f, double& origin_above_floor) {
    app.add_option("--refuse-arm", f.refuse_arm, "a pre-arm check that fails: every ARM is DENIED with this reason");
    app.add_option("--lose-offboard-after", f.lose_after,
                   "seconds after arming when the offboard stream stops reaching them (0 = never)")
        ->check(dw::cli::in(kLoseAfterRange));
    app.add_option("--kill-after", f.kill_after,
                   dw::log::cat("seconds after arming when the kill switch is thrown; PX4 disarms ",
                                dw::px4sim::SimulatedPx4Options{}.com_kill_disarm_s, " s later (0 = never)"))
        ->check(dw::cli::in(kLoseAfterRange));
    app.add_option("--low-battery-after", f.low_battery_after,
                   "seconds after arming when the battery reaches its failsafe level: PX4 lands (0 = never)")
        ->check(dw::cli::in(kLoseAfterRange));
    app.add_option("--origin-above-floor", origin_above_floor,
                   dw::log::cat("where each PX4's local origin is, above the floor [m] (default: as PX4 does it — ",
                                dw::px4sim::kOnboardOriginAboveFloor_m,
                                " m on its own sensors, where GPS and barometer put it; 0 on vision)"))
        ->check(dw::cli::in(kOriginAboveFloorRange));
    app.add_flag("--land-detector-fooled", f.land_detector_fooled,
                 "each PX4's land detector says airborne as its take-off ramp starts while the vehicle never leaves "
                 "the ground (as a real v1.15.4 SITL did)");
    app.add_option(
           "--time-jump-every", f.time_jump_every,
           dw::log::cat("each PX4's time synchroniser resets this often [s] (0: never; default ",
                        dw::px4sim::kTimeJumpEvery_s, ", as a real v1.15.4 SITL did): for ", dw::px4sim::kTimeResync_s,
                        " s its outgoing stamps are its boot time and incoming ones read as now"))
        ->check(dw::cli::in(kTimeJumpEveryRange));
}

// dw-px4-sim's one command: simulated PX4 vehicles, until stopped.
struct Px4SimCommand final : dw::cli::Command {
    explicit Px4SimCommand(dw::dds::ProcessCli& c) : cli(c) {}
    dw::dds::ProcessCli& cli;
    std::vector<std::string> names{"v1"};
    std::string px4_file, physics_file, position_source = dw::px4sim::kPositionSourceNames[0];
    std::uint16_t natnet_port = 0;
    Faults faults;
    double origin_above_floor = 0;
    bool no_motion_capture = false;

    CLI::App* add(CLI::App& app) override {
        app.add_option("--vehicles", names, "the plan's vehicles, comma-separated (each a PX4)")->delimiter(',');
        app.add_option("--px4", px4_file, "the planner's PX4 settings file (version, namespaces, MAV_SYS_IDs, frames)");
        add_fault_options(app, faults, origin_above_floor);
        app.add_option("--natnet-port", natnet_port,
                       "play the motion capture as an emulated NatNet server on 127.0.0.1:PORT for dw-mocap-bridge "
                       "(0 = publish vehicles/state directly)")
            ->check(dw::cli::in(dw::natnet::kPortRange));
        app.add_option("--position-source", position_source,
                       "where each PX4's estimator gets its position: vision (the lab's vehicle_visual_odometry) or "
                       "onboard (its own sensors: GPS, SITL's ground truth)");
        app.add_flag(
            "--no-motion-capture", no_motion_capture,
            "play no motion capture at all (neither vehicles/state nor NatNet): the lab's poses come from PX4's "
            "estimate (dw-mocap-bridge --source px4)");
        app.add_option("--physics", physics_file,
                       "physics configuration: the stand's height, where the sufferer's body is (--natnet-port)");
        return &app;
    }
    int run() override {
        CLI::App& app = cli.app();
        const auto source_index = dw::find_name(dw::px4sim::kPositionSourceNames, position_source);
        if (!source_index)
            throw dw::InputError("--position-source: " + dw::unknown_name_problem("position source", position_source,
                                                                                  dw::px4sim::kPositionSourceNames));
        const auto source = static_cast<dw::px4sim::PositionSource>(*source_index);
        if (no_motion_capture && natnet_port != 0) throw dw::InputError("--natnet-port: not with --no-motion-capture");
        const double stand_height_m = dw::physics::physics_or_defaults(physics_file).stand.height_m;
        const auto options = app.count("--px4") == 0 ? dw::planner::default_px4_options(names)
                                                     : dw::planner::load_px4_options(px4_file, names);
        dw::dds::Participant lab(cli.dds(), "px4_sim", cli.clock());
        dw::dds::Heartbeat heartbeat(lab);  // the planner and dw-lab wait for it (--wait-for px4_sim)
        if (app.count("--origin-above-floor") > 0) faults.origin_above_floor = origin_above_floor;
        const auto sims = start_vehicles(lab, cli, options, faults, natnet_port == 0 && !no_motion_capture, source);
        const auto mocap = natnet_port == 0 ? nullptr : motion_capture(natnet_port, stand_height_m, names, sims);
        if (mocap) std::cout << "motion capture: emulated NatNet server on 127.0.0.1:" << mocap->port() << std::endl;
        heartbeat.set_state(dw::msg::PROC_RUNNING);
        while (!dw::Shutdown::instance().wait_for(std::chrono::seconds(1))) {}
        for (std::size_t i = 0; i < sims.size(); ++i) {
            const auto r = sims[i]->report();
            std::cout << options.vehicles[i].name << ": " << (r.was_armed ? "armed" : "never armed") << ", "
                      << r.ignored_commands << " commands ignored (another system), " << r.undecodable
                      << " payloads undecodable\n";
        }
        return 0;
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli(
        "dw-px4-sim: simulated PX4 vehicles (uXRCE-DDS topics, Commander rules) for dw-planner --vehicles px4");
    Px4SimCommand sim(cli);
    return dw::cli::run_commands(cli.app(), {&sim}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-px4-sim", [&] { return run(argc, argv); });
}
