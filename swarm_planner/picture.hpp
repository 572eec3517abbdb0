#pragma once
// The plan as a picture (PNG, headless OpenCV): top view (N up, E right) and side view (E right,
// height up) with the geofence, the measured square, the stand, every leg's measured segment per
// vehicle (coloured by altitude) and the transitions.
#include <string>

#include "swarm_planner/plan.hpp"

namespace dw::planner {

// Throws dw::RuntimeError when the file cannot be written.
void draw_plan(const Plan& p, const std::string& png_path);

}  // namespace dw::planner
