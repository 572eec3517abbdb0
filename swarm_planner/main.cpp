// dw-planner: formations, grid legs, safe trajectories. `plan` writes a checked plan and its
// picture; `run` flies it: the supervised experiment over DDS, with simulated or PX4 vehicles.
#include <filesystem>
#include <iostream>
#include <sstream>

#include "core/shutdown.hpp"
#include "dds/process_cli.hpp"
#include "swarm_planner/experiment.hpp"
#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/numbers.hpp"
#include "plot/png.hpp"
#include "core/log.hpp"
#include "swarm_planner/picture.hpp"
#include "swarm_planner/plan.hpp"

namespace {

// `dw-planner run`: the supervised experiment. DONE exits 0; ABORTED is a runtime failure.
int fly(dw::dds::ProcessCli& cli, const dw::planner::Plan& p, dw::planner::RunOptions ro, const std::string& wait) {
    dw::dds::Participant participant(cli.dds(), "planner", cli.clock());
    dw::dds::Heartbeat heartbeat(participant);
    heartbeat.set_state(dw::msg::PROC_RUNNING);
    ro.wait_for.clear();
    std::stringstream w(wait);
    for (std::string item; std::getline(w, item, ',');) {
        if (!item.empty()) ro.wait_for.push_back(item);
    }
    dw::planner::Experiment experiment(participant, p, ro);
    const auto phase = experiment.run();
    if (phase == dw::msg::PHASE_DONE) {
        std::cout << "DONE: " << experiment.legs_flown() << " of " << p.reference.legs().size() << " legs flown\n";
        return 0;
    }
    std::cout << "ABORTED: " << experiment.reason() << "\n";
    if (dw::Shutdown::instance().requested())
        throw dw::Stopped("stopped: the experiment was aborted and the vehicles landed");
    throw dw::RuntimeError("ABORTED: " + experiment.reason());
}

// What plan and run share: the plan's options, and the checked plan they make.
struct PlanArgs {
    dw::planner::PlanOptions o;
    std::string altitudes = "0.3,0.8,1.3";

    void add(CLI::App* sub) {
        sub->add_option("--formation", o.formation,
                        "single, side_by_side, leader_follower, leader_follower3, stack or hybrid")
            ->required();
        sub->add_option("--altitudes", altitudes,
                        "relative altitudes above the sufferer [m], comma-separated (<= 1.4)");
        sub->add_option("--legs", o.grid.legs, "number of legs (30-40 in the study)")
            ->check(dw::cli::in(dw::physics::kLegsRange));
        sub->add_option("--speed", o.grid.speed_mps, "leg speed [m/s]")->check(dw::cli::in(dw::physics::kSpeedRange));
        sub->add_option("--min-separation", o.min_separation_m, "between vehicles and from the sufferer [m]")
            ->check(dw::cli::in(dw::planner::kSeparationRange));
    }
    // The plan's altitudes read from the line (the first check of both commands).
    void read() {
        o.grid.altitudes_m = dw::parse_number_list(altitudes, dw::planner::kPlanAltitudeRange, "--altitudes");
    }
    // The plan; an infeasible one is the user's error.
    dw::planner::Plan make(std::stop_token stop) const {
        auto p = dw::planner::make_plan(o);
        if (const auto v = dw::planner::check(p, stop)) throw dw::InputError("infeasible plan: " + v->what);
        return p;
    }
};

// `dw-planner plan`: a checked plan and its picture.
struct PlanCommand final : dw::cli::Command {
    PlanArgs args;
    std::string out = "plan.yaml", picture;

    CLI::App* add(CLI::App& app) override {
        auto* sub = app.add_subcommand("plan", "write a checked plan (YAML, or JSON by extension) and a picture (PNG)");
        args.add(sub);
        sub->add_option("--out", out, "plan file (.yaml or .json)");
        sub->add_option("--picture", picture, "PNG picture (default: the plan file with .png)");
        return sub;
    }
    int run() override {
        args.read();
        const bool json = std::filesystem::path(out).extension() == ".json";
        dw::require_writable_path(out, "--out");  // both outputs checked before any work
        if (picture.empty()) picture = std::filesystem::path(out).replace_extension(".png").string();
        dw::plot::require_png_path(picture, "--picture");
        const auto stop = dw::Shutdown::instance().token();
        const auto p = args.make(stop);
        const double covered = dw::planner::coverage(p, stop);  // before any file: a stop leaves none
        dw::write_file(out, dw::planner::to_document(p, json));
        dw::planner::draw_plan(p, picture);
        std::cout << p.reference.legs().size() << " legs, " << p.duration_s() << " s, coverage "
                  << static_cast<int>(covered * 100 + 0.5)
                  << " % of the square; every pair >= " << args.o.min_separation_m
                  << " m apart and inside the geofence; wrote " << out << " and " << picture << "\n";
        return 0;
    }
};

// `dw-planner run`: fly the plan.
struct RunCommand final : dw::cli::Command {
    explicit RunCommand(dw::dds::ProcessCli& c) : cli(c) {}
    dw::dds::ProcessCli& cli;
    PlanArgs args;
    dw::planner::RunOptions ro;
    std::string wait = "stand_agent,mocap_bridge,recorder", link = "sim", px4_file;
    CLI::App* sub = nullptr;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("run", "fly the plan: the supervised experiment over DDS (vehicles: sim or px4)");
        args.add(sub);
        sub->add_option("--wait-for", wait, "processes to wait for (heartbeats), comma-separated; '' = none");
        sub->add_option("--run-id", ro.run_id, "experiment run id (default: run-<unix time>)");
        sub->add_option("--wait-timeout", ro.wait_timeout_s, "seconds to wait for the participants")
            ->check(dw::cli::in(dw::kTimeoutRange));
        sub->add_option("--rejoin-grace", ro.rejoin_grace_s,
                        "seconds a lost required process may take to come back (a restarted recorder) before the "
                        "experiment aborts; 0 = abort at once")
            ->check(dw::cli::in(dw::planner::kRejoinGraceRange));
        sub->add_option("--tracking-bound", ro.tracking_error_m,
                        "in flight, a vehicle farther than this from its setpoint aborts the experiment [m]")
            ->check(dw::cli::in(dw::planner::kTrackingBoundRange));
        sub->add_option("--takeoff-time", ro.takeoff_s,
                        "the take-off curve's duration, parked to the first setpoint [s]")
            ->check(dw::cli::in(dw::planner::kTakeoffTimeRange));
        sub->add_option("--takeoff-settle", ro.takeoff_settle_s,
                        "after the take-off curve, the longest the vehicles may take to come within the tracking bound "
                        "of their first setpoints (a PX4 spools up and climbs on its ramp first) [s]")
            ->check(dw::cli::in(dw::planner::kTakeoffSettleRange));
        sub->add_option("--vehicles", link, "sim (vehicles/setpoint) or px4 (PX4's uXRCE-DDS topics)");
        sub->add_option("--px4", px4_file,
                        "with --vehicles px4: the PX4 settings file (version, each vehicle's namespace, MAV_SYS_ID, "
                        "origin, heading; docs/OPERATOR.md)");
        return sub;
    }
    int run() override {
        args.read();
        ro.stop = dw::Shutdown::instance().token();
        const auto p = args.make(ro.stop);
        ro.tracking_bound_source = sub->count("--tracking-bound") > 0 ? "set by --tracking-bound" : "the default";
        ro.link = dw::planner::parse_link(link, "--vehicles");
        if (sub->count("--px4") > 0) {  // given: "" is a missing file, not "no file"
            if (ro.link != dw::planner::LinkKind::px4) throw dw::InputError("--px4: only with --vehicles px4");
            ro.px4 = dw::planner::load_px4_options(px4_file, p.vehicles);
        }
        return fly(cli, p, ro, wait);
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-planner: plan formation flights over the load stand, and fly them");
    CLI::App& app = cli.app();
    app.require_subcommand(1);
    PlanCommand plan;
    RunCommand run(cli);
    return dw::cli::run_commands(app, {&plan, &run}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-planner", [&] { return run(argc, argv); });
}
