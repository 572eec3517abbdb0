#include "analysis/conceal.hpp"

#include "core/log.hpp"
#include "physics/effect_types.hpp"
#include "physics/recording_chain.hpp"
#include "physics/samplers.hpp"

namespace dw::analysis {

// The recording-side effects of fx put into a recorded flight through the recording chain, on the
// recording's own samples (it keeps its own tare: the calibration is linear, so its zero moves
// with it).
void conceal(flight::Flight& f, const physics::Effects& fx) {
    physics::ChainInput in;
    for (const auto& s : f.wrench) in.t.push_back(s.t), in.force.push_back(s.w);
    physics::OwnSampler own;
    const auto s = physics::RecordingChain(fx).record(std::move(in), own);
    for (std::size_t i = 0; i < s.w.size(); ++i) f.wrench[i] = {s.stamps[i], s.w[i]};
}

Concealed concealed_sizes(ConcealedSize which) {
    Concealed out;
    for (const auto* t : physics::effect_types())
        if (const auto c = t->real_concealment())
            out[t->name()] = which == ConcealedSize::single ? c->single : c->session;
    return out;
}

bool on_concealed_axes(const physics::EffectType& t, physics::AxisPair axes) {
    const auto c = t.real_concealment();
    return !t.has_axes() || (c && axes == c->axes);
}

namespace {

// One effect's concealment at one size.
Concealment concealment_of(const physics::EffectType& t, const physics::RealConcealment& c, double size) {
    return {t.name(), log::cat(c.said_before, size, c.said_after),
            [&t, c, size](flight::Flight& f) {
                physics::Effects fx;
                t.set(fx, {size}, c.axes);
                conceal(f, fx);
            },
            [&t, c, size](const physics::Effects& own, std::optional<double> u) {
                const double mine = (on_concealed_axes(t, t.axes(own)) ? t.in_force(own) : t.neutral()).front();
                const double before = u.value_or(mine);
                return Truth{t.name(), t.parameters().front().name, c.multiplies ? before * size : before + size};
            }};
}

}  // namespace

std::vector<Concealment> concealments(const Concealed& m) {
    std::vector<Concealment> out;
    for (const auto* t : physics::effect_types())
        if (const auto c = t->real_concealment(); c && m.count(t->name()))
            out.push_back(concealment_of(*t, *c, m.at(t->name())));
    return out;
}

std::string concealment_names() {
    std::vector<std::string> names;
    for (const auto* t : physics::effect_types())
        if (t->real_concealment()) names.push_back(t->name());
    return log::join(names);
}

}  // namespace dw::analysis
