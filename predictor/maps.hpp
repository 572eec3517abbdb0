#pragma once
// Force maps drawn headless with OpenCV (PNG): the force on the sufferer over an N-E grid of the
// formation's position at a relative altitude — observed (binned recorded data) beside each
// model, on one diverging colour scale with a colour bar, axes in metres and vehicle outlines —
// and line plots of the force along E through the stand (the study's Fig. 7).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "predictor/dataset.hpp"
#include "plot/field_map.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

using plot::colour_of;
using plot::Field;
using plot::MapLayout;
using plot::Outline;
using plot::render_fields;

struct MapRequest {
    std::string formation = "leader_follower3";  // physics formation name (offsets of the vehicles)
    double altitude_m = 1.3;                     // the formation's reference point above the sufferer
    double speed_mps = 0.5;                      // along +E
    int axis = kFdAxis;                          // f_d
    double half_width_m = 1.2;
    int cells = 61;
    std::optional<Dataset> observed;  // recorded samples of this formation (binned, legs both ways)
    double band_m = 0.15;
};

Field model_field(const ForceModel& model, const MapRequest& r);
Field observed_field(const Dataset& d, const MapRequest& r, double cell_m = 0.1);

MapLayout draw_force_map(const std::vector<const ForceModel*>& models, const MapRequest& r, const std::string& png);
void draw_force_line(const std::vector<const ForceModel*>& models, const MapRequest& r, const std::string& png);

}  // namespace dw::predictor
