// dw-px4-sim: simulated PX4 vehicles on the lab's domain (px4_sim/simulated_px4.hpp) — PX4's
// uXRCE-DDS topics and Commander rules, each vehicle also playing its motion capture — so that
// `dw-planner run --vehicles px4` can be tried on one machine. Not a flight simulator: each
// vehicle closes on its setpoint at a fixed rate.
#include <iostream>

#include "core/cli.hpp"
#include "core/shutdown.hpp"
#include "dds/process_cli.hpp"
#include "px4_sim/simulated_px4.hpp"

namespace {

constexpr dw::Range kLoseAfterRange{0, 3600, "s"};
constexpr double kParkedNorth_m = -1.5, kParkedEast0_m = -2.0, kParkedSpacing_m = 1.0;  // in a row at the fence's south side

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-px4-sim: simulated PX4 vehicles (uXRCE-DDS topics, Commander rules) for dw-planner --vehicles px4");
    CLI::App& app = cli.app();
    std::vector<std::string> names{"v1"};
    std::string px4_file, refuse_arm;
    double lose_after = 0;
    app.add_option("--vehicles", names, "the plan's vehicles, comma-separated (each a PX4)")->delimiter(',');
    app.add_option("--px4", px4_file, "the planner's PX4 settings file (version, namespaces, MAV_SYS_IDs, frames)");
    app.add_option("--refuse-arm", refuse_arm, "a pre-arm check that fails: every ARM is DENIED with this reason");
    app.add_option("--lose-offboard-after", lose_after, "seconds after arming when the offboard stream stops reaching them (0 = never)")
        ->check(dw::cli::in(kLoseAfterRange));
    cli.parse(argc, argv);
    const auto options = app.count("--px4") == 0 ? dw::planner::default_px4_options(names) : dw::planner::load_px4_options(px4_file, names);
    dw::dds::Participant lab(cli.dds(), "px4_sim", cli.clock());
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
        o.refuse_arm = refuse_arm;
        if (lose_after > 0) o.lose_offboard_after_s = lose_after;
        sims.push_back(std::make_unique<dw::px4sim::SimulatedPx4>(lab, cli.dds(), o));
        std::cout << v.name << ": simulated PX4 " << dw::dds::px4_version(options.version).name << ", MAV_SYS_ID " << v.system_id << ", topics "
                  << dw::dds::px4_topic(v.ns, "in", "...") << std::endl;
    }
    while (!dw::Shutdown::instance().wait_for(std::chrono::seconds(1))) {}
    for (std::size_t i = 0; i < sims.size(); ++i) {
        const auto r = sims[i]->report();
        std::cout << options.vehicles[i].name << ": " << (r.was_armed ? "armed" : "never armed") << ", " << r.ignored_commands
                  << " commands ignored (another system), " << r.undecodable << " payloads undecodable\n";
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-px4-sim", [&] { return run(argc, argv); });
}
