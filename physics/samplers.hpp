#pragma once
// How the recording chain's felt series becomes a recording's samples (RecordingChain::record's
// Sampler): the load stand's eight chips (the simulator), a flying sufferer's residual at its rate
// (the simulator), a sampler that matches the chips at a recording's own stamps (the replay), and
// a recording's own samples (a concealment).
#include <vector>

#include "physics/config.hpp"
#include "physics/recording_chain.hpp"
#include "physics/stand.hpp"
#include "physics/vehicle.hpp"

namespace dw::physics {

// The series w on the uniform grid t, read at time x by linear interpolation (held at its ends).
Wrench6 interpolate(const std::vector<double>& t, const RecordedWrench& w, double x);

// Eight HX711s on their own oscillators (rates within ±rate_skew, random phases and offsets),
// each converting its cell's force with the stand's noise into counts; a sample whenever chip 0
// converts, holding every chip's latest counts (what the stand agent publishes), as the wrench
// those counts give, untared.
class ChipSampler final : public Sampler {
public:
    ChipSampler(const StandParams& p, Rng& rng) : p_(p), stand_(p), rng_(rng) {}
    Samples sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) override;
    // As the stand agent tares: the mean counts of the first tare_s subtracted from every frame's.
    void tare(Samples& s, double tare_s) const override;

    using Counts = Eigen::Matrix<double, kCells, 1>;

private:
    const StandParams& p_;
    StandModel stand_;
    Rng& rng_;
    std::vector<Counts> counts_;  // the last samples' frames
};

// A flying sufferer's residual: the felt wrench every 1/rate_hz, the stand's noise on its forces.
class RateSampler final : public Sampler {
public:
    RateSampler(double rate_hz, double noise_n, Rng& rng) : rate_hz_(rate_hz), noise_n_(noise_n), rng_(rng) {}
    Samples sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) override;

private:
    double rate_hz_, noise_n_;
    Rng& rng_;
};

// At a recording's own stamps, what the chips give on average: chip 0 converting at the sample's
// time, each of the other seven holding a conversion half a period old (its latest, of a uniform
// age); with no stand (a residual source) the felt wrench at the sample's time.
class StampSampler final : public Sampler {
public:
    StampSampler(const std::vector<double>& stamps, const StandParams* stand);
    Samples sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) override;

private:
    const std::vector<double>& stamps_;
    double hold_s_ = 0;
    Eigen::Matrix<double, 6, 6> fresh_;  // the share of the wrench chip 0's cell carries (the rest is the held cells')
};

// The felt series' own samples, its stamps late by the clock (a recording given new effects).
class OwnSampler final : public Sampler {
public:
    Samples sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) override;
};

}  // namespace dw::physics
