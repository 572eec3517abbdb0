#include "physics/samplers.hpp"

#include <algorithm>
#include <array>
#include <cstdint>

namespace dw::physics {

Wrench6 interpolate(const std::vector<double>& t, const RecordedWrench& w, double x) {
    if (w.size() < 2 || !(x > t.front())) return w.front();
    const double g = (x - t.front()) / (t[1] - t.front());
    const auto i = static_cast<std::size_t>(g);
    if (i + 1 >= w.size()) return w.back();
    const double a = g - static_cast<double>(i);
    return to_wrench6((1 - a) * to_wrench(w[i]) + a * to_wrench(w[i + 1]));
}

namespace {

using Counts = ChipSampler::Counts;

struct Chip {
    double period, phase, offset;
    std::vector<double> t;
    std::vector<std::int32_t> counts;
};

// The frames: when chip 0 converts, every chip's latest counts (none until each has converted).
std::vector<Counts> frames(const std::array<Chip, kCells>& chips, std::vector<double>& t) {
    std::array<std::size_t, kCells> latest{};
    std::vector<Counts> out;
    for (const double t0 : chips[0].t) {
        Counts counts;
        bool complete = true;
        for (std::size_t ci = 0; ci < kCells; ++ci) {
            while (latest[ci] + 1 < chips[ci].t.size() && chips[ci].t[latest[ci] + 1] <= t0) ++latest[ci];
            if (chips[ci].t.empty() || chips[ci].t[latest[ci]] > t0) complete = false;
            else counts[static_cast<Eigen::Index>(ci)] = chips[ci].counts[latest[ci]];
        }
        if (!complete) continue;
        t.push_back(t0);
        out.push_back(counts);
    }
    return out;
}

}  // namespace

Samples ChipSampler::sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) {
    std::array<Chip, kCells> chips;
    for (int ci = 0; ci < kCells; ++ci) {
        Chip& chip = chips[static_cast<std::size_t>(ci)];
        chip.period = 1.0 / (p_.rate_hz * (1.0 + p_.rate_skew * (2 * rng_.uniform() - 1)));
        chip.phase = chip.period * rng_.uniform();
        chip.offset = p_.offset_sigma_counts * rng_.normal();
        for (double x = chip.phase; x <= t.back(); x += chip.period) {
            const auto cells = stand_.wrench_to_cells(to_wrench(interpolate(t, felt, x)));
            const double force = cells[ci] + p_.noise_n * rng_.normal();
            chip.t.push_back(x);
            chip.counts.push_back(StandModel::to_counts(force, chip.offset, p_.counts_per_newton));
        }
    }
    std::vector<double> at;
    counts_ = frames(chips, at);
    Samples out;
    for (std::size_t i = 0; i < at.size(); ++i) {
        out.stamps.push_back(at[i] + clock_delay_s);
        out.w.push_back(to_wrench6(stand_.cells_to_wrench() * (counts_[i] / p_.counts_per_newton)));
    }
    return out;
}

void ChipSampler::tare(Samples& s, double tare_s) const {
    const std::size_t n = tare_count(s.stamps, tare_s);
    if (n == 0) return;  // sample() made every frame's wrench from its counts as they are
    Counts zero = Counts::Zero();
    for (std::size_t i = 0; i < n; ++i) zero += counts_[i];
    zero /= static_cast<double>(n);
    for (std::size_t i = 0; i < s.w.size(); ++i)
        s.w[i] = to_wrench6(stand_.cells_to_wrench() * ((counts_[i] - zero) / p_.counts_per_newton));
}

Samples RateSampler::sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) {
    Samples out;
    for (std::size_t i = 0; static_cast<double>(i) / rate_hz_ <= t.back(); ++i) {
        const double x = static_cast<double>(i) / rate_hz_;
        Wrench6 w = interpolate(t, felt, x);
        for (std::size_t a = 0; a < 3; ++a) w[a] += noise_n_ * rng_.normal();
        out.stamps.push_back(x + clock_delay_s);
        out.w.push_back(w);
    }
    return out;
}

StampSampler::StampSampler(const std::vector<double>& stamps, const StandParams* stand) : stamps_(stamps) {
    fresh_.setIdentity();  // no stand: every sample is fresh
    if (!stand) return;
    const StandModel model(*stand);
    hold_s_ = 0.5 / stand->rate_hz;
    fresh_ = model.cells_to_wrench().col(0) * model.wrench_to_cells().row(0);  // chip 0's cell alone
}

Samples StampSampler::sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) {
    Samples out{stamps_, RecordedWrench(stamps_.size())};
    for (std::size_t i = 0; i < stamps_.size(); ++i) {
        const double x = stamps_[i] - clock_delay_s;
        const Wrench now = to_wrench(interpolate(t, felt, x));
        const Wrench held = hold_s_ > 0 ? to_wrench(interpolate(t, felt, x - hold_s_)) : now;
        out.w[i] = to_wrench6(held + fresh_ * (now - held));
    }
    return out;
}

Samples OwnSampler::sample(const std::vector<double>& t, const RecordedWrench& felt, double clock_delay_s) {
    Samples out{t, felt};
    for (auto& s : out.stamps) s += clock_delay_s;
    return out;
}

}  // namespace dw::physics
