#include "predictor/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "physics/bodies.hpp"
#include "recordings/recordings.hpp"

namespace dw::predictor {

std::array<double, 3> Sample::reference() const {
    std::array<double, 3> c{0, 0, 0};
    if (k == 0) return c;
    c[2] = -1e9;
    for (std::size_t j = 0; j < static_cast<std::size_t>(k); ++j) {
        c[0] += x[j][0] / k;
        c[1] += x[j][1] / k;
        c[2] = std::max(c[2], x[j][2]);  // the lowest neighbour: largest D
    }
    c[2] = -c[2];  // height above the sufferer
    return c;
}

void Dataset::append(const Dataset& other) {
    const int base = static_cast<int>(sources.size());
    sources.insert(sources.end(), other.sources.begin(), other.sources.end());
    for (auto s : other.samples) {
        s.source += base;
        samples.push_back(s);
    }
}

Dataset Dataset::with_formation(const std::string& formation) const {
    Dataset d;
    d.sources = sources;
    for (const auto& s : samples)
        if (sources[static_cast<std::size_t>(s.source)].formation == formation) d.samples.push_back(s);
    return d;
}

Dataset Dataset::with_reference() const {
    Dataset d;
    d.sources = sources;
    for (const auto& s : samples)
        if (!sources[static_cast<std::size_t>(s.source)].reference.empty()) d.samples.push_back(s);
    return d;
}

Dataset Dataset::in_altitude_band(double altitude_m, double band_m) const {
    Dataset d;
    d.sources = sources;
    for (const auto& s : samples)
        if (s.k > 0 && std::abs(s.reference()[2] - altitude_m) <= band_m) d.samples.push_back(s);
    return d;
}

Dataset Dataset::with_k(int k_min, int k_max) const {
    Dataset d;
    d.sources = sources;
    for (const auto& s : samples)
        if (s.k >= k_min && s.k <= k_max) d.samples.push_back(s);
    return d;
}

Dataset Dataset::from_two_vehicle_flights() const {
    Dataset d;
    d.sources = sources;
    for (const auto& s : samples)
        if (sources[static_cast<std::size_t>(s.source)].neighbours.size() == 1) d.samples.push_back(s);
    return d;
}

Split split_by_leg(const Dataset& d, int period, int test_phase, int val_phase) {
    Split s;
    s.train = d.legs_where([&](int leg) { return leg % period != test_phase && leg % period != val_phase; });
    s.validation = d.legs_where([&](int leg) { return leg % period == val_phase; });
    s.test = d.legs_where([&](int leg) { return leg % period == test_phase; });
    return s;
}

namespace {

// reference.csv read at increasing times: linear between its rows, none outside them.
class ReferenceCursor {
public:
    explicit ReferenceCursor(const std::vector<flight::WrenchSample>& r) : r_(r) {}
    Wrench6 at(double t) {
        if (r_.empty() || t < r_.front().t || t > r_.back().t) return kNoPrediction;
        while (i_ + 1 < r_.size() && r_[i_ + 1].t < t) ++i_;
        const auto& a = r_[i_];
        const auto& b = r_[std::min(i_ + 1, r_.size() - 1)];
        const double w = b.t > a.t ? (t - a.t) / (b.t - a.t) : 0.0;
        Wrench6 out;
        for (std::size_t k = 0; k < 6; ++k) out[k] = a.w[k] + w * (b.w[k] - a.w[k]);
        return out;
    }

private:
    const std::vector<flight::WrenchSample>& r_;
    std::size_t i_ = 0;
};

}  // namespace

Dataset from_flight(const flight::Flight& f, const std::string& name, const DatasetOptions& o) {
    const auto bodies = flight::body_tracks(f, name + "/");
    const auto& ns = bodies.neighbours;
    if (ns.size() > static_cast<std::size_t>(kMaxNeighbours))
        throw InputError(
            log::cat(name, "/meta.json: neighbours: ", ns.size(), " (the models take at most ", kMaxNeighbours, ")"));
    const auto& st = bodies.sufferer;
    const auto blocks = flight::find_blocks(f, kSplitPeriod, physics::encounter_radii(f.meta, o.physics));

    Dataset d;
    std::string formation = f.meta.formation;
    if (ns.size() > 1 || formation == "single") formation += log::cat(" K=", ns.size());
    Source src;  // by name: a positional {} here once left every axis unmeasured (RMSE "–" on stand flights)
    src.name = name;
    src.formation = formation;
    src.sufferer = physics::vehicle_of(f.meta, f.meta.sufferer, o.physics.sufferer.vehicle);
    src.neighbours = physics::neighbours_of(f.meta, o.physics);
    src.flying = !f.meta.stand_height_m.has_value();
    src.blocks = blocks.kind;
    if (!f.meta.moments_measured) src.measured = {true, true, true, false, false, false};
    if (f.meta.reference) src.reference = f.meta.reference->source;
    src.estimated_poses = f.meta.pose_source == flight::PoseSource::estimate;
    d.sources.push_back(src);
    ReferenceCursor reference(f.reference);
    flight::BlockCursor block(blocks.blocks);
    for (const auto& w : f.wrench) {
        if (w.t < st.t.front() || w.t > st.t.back()) continue;
        Sample s;
        s.t = w.t;
        s.y = w.w;
        s.recorded_prediction = reference.at(w.t);
        const auto ps = st.position_at(w.t);
        const auto vs = st.velocity_at(w.t);
        s.height = -ps[2];
        for (std::size_t j = 0; j < ns.size(); ++j) {
            const auto& tr = ns[j];
            if (w.t < tr.t.front() || w.t > tr.t.back()) continue;
            const auto p = tr.position_at(w.t);
            const auto v = tr.velocity_at(w.t);
            RelState r{p[0] - ps[0], p[1] - ps[1], p[2] - ps[2], v[0] - vs[0], v[1] - vs[1], v[2] - vs[2]};
            if (std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) > o.max_distance_m) continue;
            s.who[static_cast<std::size_t>(s.k)] = static_cast<std::uint8_t>(j);
            s.x[static_cast<std::size_t>(s.k++)] = r;
        }
        if (const auto* leg = block.at(w.t)) {
            s.leg = leg->leg;
            if (blocks.kind != flight::BlockKind::legs) {
                d.samples.push_back(s);
                continue;
            }
            double ve = 0;
            for (int j = 0; j < s.k; ++j) ve += s.x[static_cast<std::size_t>(j)][4];
            s.leg_direction = ve > 0 ? 1 : (ve < 0 ? -1 : 0);
        }
        d.samples.push_back(s);
    }
    return d;
}

Dataset load_dataset(const std::string& path, const DatasetOptions& o) {
    return from_flight(recordings::read_flight_or_recording(path), path, o);
}

}  // namespace dw::predictor
