#pragma once
// reference.csv (../shared/FLIGHT_FORMAT.md): another model's prediction of the wrench, on the
// wrench's clock, wrench.csv's columns; a cell is empty exactly where the model predicts nothing
// (an axis not in meta.json's reference.axes). Internal to dw_flight.
#include <string>
#include <vector>

#include "flight/flight.hpp"

namespace dw::flight {

// Throws dw::InputError naming the file, line and column (a number where the model predicts
// nothing, an empty cell where it does, unsorted rows, no rows).
std::vector<WrenchSample> read_reference_csv(const std::string& path, const ReferenceInfo& info);
// The file's text; NaN cells of the axes not predicted become empty. Throws dw::InputError for a
// value that cannot be written (a non-finite number on a predicted axis: row and column).
std::string reference_csv(const std::vector<WrenchSample>& samples, const ReferenceInfo& info);

}  // namespace dw::flight
