#pragma once
// Per-body physics for recorded flights: each vehicle's parameters come from the flight's
// meta.json (a small vehicle under a large one is not two identical vehicles); the physics
// configuration's own values serve only a body the flight does not describe.
#include <string>
#include <vector>

#include "flight/flight.hpp"
#include "physics/config.hpp"

namespace dw::physics {

// How far (in the neighbour's own diagonal motor distances) a neighbour counts as near the
// sufferer horizontally: its jet's half-width stays below a few sizes at the separations flown.
inline constexpr double kNearSizes = 6.0;
// ... and within how many sizes a pass of a neighbour is an encounter (a cross-validation block).
inline constexpr double kEncounterSizes = 2.5;

// The body's parameters from meta.json, or `fallback` when the flight does not list it.
VehicleParams vehicle_of(const flight::Meta& m, const std::string& body, const VehicleParams& fallback);

// c with the flight's sufferer as the sufferer's vehicle. Throws dw::InputError naming the body
// when its parameters would make the physics produce NaN or nothing (a disc or arm of zero size).
PhysicsConfig for_flight(PhysicsConfig c, const flight::Meta& m);

// The horizontal distance within which `neighbour` counts as near the sufferer.
double near_radius(const VehicleParams& neighbour);
// A noise floor (the recorded spread where nobody is near) is measured on at least this many
// samples (the explainer's, a vehicle class's, a prediction interval's).
inline constexpr std::size_t kMinFarSamples = 30;
// Every neighbour's parameters, in meta.json's order; and their encounter radii.
std::vector<VehicleParams> neighbours_of(const flight::Meta& m, const PhysicsConfig& c);
std::vector<double> encounter_radii(const flight::Meta& m, const PhysicsConfig& c);

}  // namespace dw::physics
