#pragma once
// A recorded flight replayed under a physics configuration (`dw-sim replay`): the wrench the
// physics predicts along the flight's own poses, seen the way the recording sees it
// (Resimulation::recorded, without noise), and the configuration's learnt discrepancy at the same
// stamps when it carries one (analysis/discrepancy.hpp). `dw-sim fly` adds the discrepancy to a
// flight it simulates the same way.
#include <vector>

#include "analysis/resimulation.hpp"
#include "flight/flight.hpp"
#include "physics/config.hpp"

namespace dw::analysis {

struct Replay {
    std::vector<Wrench6> physics;      // at every wrench stamp of the flight
    std::vector<Wrench6> discrepancy;  // the same length; zero without one
    std::vector<bool> on_blocks;       // the samples in the flight's cross-validation blocks
    std::array<bool, 6> measured_axes{};
    // physics + discrepancy, sample by sample.
    std::vector<Wrench6> with_discrepancy() const;
};
// Throws dw::InputError when the flight cannot be resimulated or the discrepancy is not this build's.
Replay replay(const flight::Flight& f, const physics::PhysicsConfig& c);

// The RMS per axis of (recorded − w) over the samples on blocks (0 on an axis not measured).
flight::AxisValues rms_on_blocks(const flight::Flight& f, const Replay& r, const std::vector<Wrench6>& w);

// b added to a, sample by sample.
void add(std::vector<Wrench6>& a, const std::vector<Wrench6>& b);
// w added to, or written over, the flight's wrench samples (one per sample).
void add_wrench(flight::Flight& f, const std::vector<Wrench6>& w);
void set_wrench(flight::Flight& f, const std::vector<Wrench6>& w);

}  // namespace dw::analysis
