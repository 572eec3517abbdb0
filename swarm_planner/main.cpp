// dw-planner: formations, grid legs, safe trajectories. `plan` writes a checked plan and its
// picture. (`run`, the supervised experiment over DDS, is not built yet.)
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "swarm_planner/picture.hpp"
#include "swarm_planner/plan.hpp"

namespace {

int run(int argc, char** argv) {
    CLI::App app{"dw-planner: plan formation flights over the load stand"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    app.require_subcommand(1);
    dw::planner::PlanOptions o;
    std::string altitudes = "0.3,0.8,1.3", out = "plan.yaml", picture;
    auto* plan = app.add_subcommand("plan", "write a checked plan (YAML, or JSON by extension) and a picture (PNG)");
    plan->add_option("--formation", o.formation, "single, side_by_side, leader_follower, leader_follower3, stack or hybrid")->required();
    plan->add_option("--altitudes", altitudes, "relative altitudes above the sufferer [m], comma-separated (<= 1.4)");
    plan->add_option("--legs", o.grid.legs, "number of legs (30-40 in the study)")->check(CLI::Range(1, 1000));
    plan->add_option("--speed", o.grid.speed_mps, "leg speed [m/s]");
    plan->add_option("--min-separation", o.min_separation_m, "between vehicles and from the sufferer [m]");
    plan->add_option("--out", out, "plan file (.yaml or .json)");
    plan->add_option("--picture", picture, "PNG picture (default: the plan file with .png)");
    dw::cli::parse(app, argc, argv);
    dw::log::set_level(dw::log::parse_level(base.log_level));
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
