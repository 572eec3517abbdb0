#include "analysis/conceal.hpp"

#include "core/log.hpp"
#include "physics/recording_chain.hpp"

namespace dw::analysis {

// The recording-side effects of fx put into a recorded flight through the recording chain: the
// sensor on the recorded stamps, the calibration, the clock (the recording keeps its own tare: the
// calibration is linear, so its zero moves with it).
void conceal(flight::Flight& f, const physics::Effects& fx) {
    const physics::RecordingChain chain(fx);
    std::vector<double> t;
    physics::RecordedWrench w;
    for (const auto& s : f.wrench) t.push_back(s.t), w.push_back(s.w);
    chain.sensor(t, w);
    for (auto& x : w) chain.calibration(x);
    const double delay = chain.clock_delay_s();
    for (std::size_t i = 0; i < w.size(); ++i) f.wrench[i] = {t[i] + delay, w[i]};
}

std::vector<Concealment> concealments(const Concealed& m) {
    return {
        {"clock_offset", log::cat("wrench stamped ", m.clock_s, " s late"),
         [m](flight::Flight& f) {
             physics::Effects fx;
             fx.clock_offset = {true, m.clock_s};
             conceal(f, fx);
         },
         [m](const physics::Effects& own, std::optional<double> u) {
             return Truth{"clock_offset", "offset_s",
                          u.value_or(own.clock_offset.enabled ? own.clock_offset.offset_s : 0) + m.clock_s};
         }},
        {"force_scale", log::cat("wrench × ", m.scale),
         [m](flight::Flight& f) {
             physics::Effects fx;
             fx.force_scale = {true, m.scale};
             conceal(f, fx);
         },
         [m](const physics::Effects& own, std::optional<double> u) {
             return Truth{"force_scale", "scale",
                          u.value_or(own.force_scale.enabled ? own.force_scale.scale : 1) * m.scale};
         }},
        {"sensor_lag", log::cat("first-order lag, tau ", m.lag_s, " s"),
         [m](flight::Flight& f) {
             physics::Effects fx;
             fx.sensor_lag = {true, m.lag_s};
             conceal(f, fx);
         },
         [m](const physics::Effects& own, std::optional<double> u) {
             return Truth{"sensor_lag", "tau_s",
                          u.value_or(own.sensor_lag.enabled ? own.sensor_lag.tau_s : 0) + m.lag_s};
         }},
        {"cell_crosstalk", log::cat("f_n += ", m.leak, " f_d"),
         [m](flight::Flight& f) {
             physics::Effects fx;
             fx.cell_crosstalk = {true, kConcealedLeakAxes.from, kConcealedLeakAxes.to, m.leak};
             conceal(f, fx);
         },
         [m](const physics::Effects& own, std::optional<double> u) {
             const auto& c = own.cell_crosstalk;
             return Truth{
                 "cell_crosstalk", "coefficient",
                 u.value_or(c.enabled && physics::AxisPair{c.from, c.to} == kConcealedLeakAxes ? c.coefficient : 0) +
                     m.leak};
         }},
    };
}

}  // namespace dw::analysis
