// dw-planner: formations, grid legs, safe trajectories. `plan` writes a checked plan and its
// picture. (`run`, the supervised experiment over DDS, is not built yet.)
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/shutdown.hpp"
#include "dds/process_cli.hpp"
#include "swarm_planner/experiment.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "swarm_planner/picture.hpp"
#include "swarm_planner/plan.hpp"

namespace {

int run(int argc, char** argv) {
    dw::Shutdown::install();
    dw::dds::ProcessCli cli("dw-planner: plan formation flights over the load stand, and fly them");
    CLI::App& app = cli.app();
    app.require_subcommand(1);
    dw::planner::PlanOptions o;
    std::string altitudes = "0.3,0.8,1.3", out = "plan.yaml", picture;
    auto* plan = app.add_subcommand("plan", "write a checked plan (YAML, or JSON by extension) and a picture (PNG)");
    auto* runc = app.add_subcommand("run", "fly the plan: the supervised experiment over DDS (vehicles: sim)");
    dw::planner::RunOptions ro;
    std::string wait = "stand_agent,mocap_bridge,recorder";
    for (auto* sub : {plan, runc}) {
        sub->add_option("--formation", o.formation, "single, side_by_side, leader_follower, leader_follower3, stack or hybrid")->required();
        sub->add_option("--altitudes", altitudes, "relative altitudes above the sufferer [m], comma-separated (<= 1.4)");
        sub->add_option("--legs", o.grid.legs, "number of legs (30-40 in the study)")->check(CLI::Range(1, 1000));
        sub->add_option("--speed", o.grid.speed_mps, "leg speed [m/s]");
        sub->add_option("--min-separation", o.min_separation_m, "between vehicles and from the sufferer [m]");
    }
    plan->add_option("--out", out, "plan file (.yaml or .json)");
    plan->add_option("--picture", picture, "PNG picture (default: the plan file with .png)");
    runc->add_option("--wait-for", wait, "processes to wait for (heartbeats), comma-separated; '' = none");
    runc->add_option("--run-id", ro.run_id, "experiment run id (default: run-<unix time>)");
    runc->add_option("--wait-timeout", ro.wait_timeout_s, "seconds to wait for the participants");
    runc->add_option("--vehicles", ro.link, "sim (vehicles/setpoint) or px4 (uXRCE-DDS: rt/<vehicle>/fmu/in/...)");
    cli.parse(argc, argv);
    o.grid.altitudes_m.clear();
    std::stringstream in(altitudes);
    for (std::string item; std::getline(in, item, ',');) {
        char* end = nullptr;
        const double a = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0') throw dw::InputError("--altitudes: '" + item + "' is not a number");
        if (a > 1.4) throw dw::InputError("--altitudes: " + item + " m is above the 1.4 m the stand's volume allows");
        o.grid.altitudes_m.push_back(a);
    }
    const auto p = dw::planner::make_plan(o);
    if (const auto v = dw::planner::check(p)) throw dw::InputError("infeasible plan: " + v->what);
    if (runc->parsed()) {
        if (ro.link != "sim" && ro.link != "px4") throw dw::InputError("--vehicles: '" + ro.link + "' (expected sim or px4)");
        ro.wait_for.clear();
        std::stringstream w(wait);
        for (std::string item; std::getline(w, item, ',');) {
            if (!item.empty()) ro.wait_for.push_back(item);
        }
        dw::dds::Participant participant(cli.dds(), "planner");
        dw::dds::Heartbeat heartbeat(participant);
        heartbeat.set_state(dw::msg::PROC_RUNNING);
        dw::planner::Experiment experiment(participant, p, ro);
        const auto phase = experiment.run();
        if (phase == dw::msg::PHASE_DONE) {
            std::cout << "DONE: " << experiment.legs_flown() << " of " << p.reference.legs().size() << " legs flown\n";
            return 0;
        }
        std::cout << "ABORTED: " << experiment.reason() << "\n";
        return dw::kExitRuntime;
    }
    const bool json = out.size() > 5 && out.substr(out.size() - 5) == ".json";
    std::ofstream(out) << dw::planner::to_document(p, json);
    if (picture.empty()) picture = out.substr(0, out.find_last_of('.')) + ".png";
    dw::planner::draw_plan(p, picture);
    std::cout << p.reference.legs().size() << " legs, " << p.duration_s() << " s, coverage "
              << static_cast<int>(dw::planner::coverage(p) * 100 + 0.5) << " % of the square; every pair >= "
              << o.min_separation_m << " m apart and inside the geofence; wrote " << out << " and " << picture << "\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-planner", [&] { return run(argc, argv); });
}
