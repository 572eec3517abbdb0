#include "swarm_planner/ground_tie.hpp"

#include <algorithm>
#include <vector>

#include "core/log.hpp"
#include "core/numbers.hpp"

namespace dw::planner {

void GroundTie::add(double t_s, const physics::Vec3& local, const physics::Vec3& velocity, bool on_ground) {
    if (!on_ground || !local.allFinite()) {
        window_.clear();
        return;
    }
    window_.push_back({t_s, local.z(), velocity.allFinite() ? velocity.norm() : INFINITY});
    while (!window_.empty() && window_.front().t < t_s - kGroundWindow_s) window_.pop_front();
    if (window_.size() < kGroundMinSamples || window_.back().t - window_.front().t < 0.9 * kGroundWindow_s) return;
    std::vector<double> d;
    judged_ = true;
    fastest_ = 0;
    for (const auto& s : window_) d.push_back(s.d), fastest_ = std::max(fastest_, s.speed);
    std::sort(d.begin(), d.end());
    spread_ = d.back() - d.front();
    if (spread_ <= kGroundSteady_m && fastest_ <= kGroundStill_mps) floor_d_ = d[d.size() / 2];
}

std::string GroundTie::describe() const {
    if (floor_d_)
        return log::cat("PX4's origin is ", fixed(*floor_d_, 2),
                        " m above the floor (its estimate on the ground, still for ", kGroundWindow_s, " s)");
    if (!judged_) return log::cat("no steady estimate on the ground yet (it is watched for ", kGroundWindow_s, " s)");
    return log::cat("its estimate on the ground is not steady: D spread ", fixed(spread_, 2), " m, speed up to ",
                    fixed(fastest_, 2), " m/s over ", kGroundWindow_s, " s (needs within ", kGroundSteady_m, " m and ",
                    kGroundStill_mps, " m/s)");
}

}  // namespace dw::planner
