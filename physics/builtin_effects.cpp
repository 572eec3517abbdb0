// The ten effects of ../shared/FLIGHT_FORMAT.md's vocabulary: one class each, with the bounds a
// configuration may give, the bounds the explainer searches, the report's words and the stage of
// the recording chain it acts at. The recording-side effects' physics is here, behind the chain's
// hooks (physics/recording_chain.hpp); the flow's is wrench_model's, a flying sufferer's own
// forces the resimulation's (analysis/resimulation.cpp).
#include <cmath>
#include <cstdlib>

#include "core/log.hpp"
#include "core/numbers.hpp"
#include "flight/flight.hpp"
#include "physics/effect_types.hpp"
#include "physics/recording_chain.hpp"

namespace dw::physics {
namespace {

using flight::kAxes;

std::string f3(double v, int p = 3) { return fixed(v, p); }

std::vector<double> range(double a, double b, int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(a + (b - a) * i / (n - 1));
    return v;
}

// A built-in whose configuration is one struct in Effects with `enabled` and one number.
template <class Field>
class OneNumber : public EffectType {
public:
    OneNumber(Field Effects::*field, double Field::*value) : field_(field), value_(value) {}
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        (e.*field_).enabled = on;
        (e.*field_).*value_ = v[0];
    }
    void clear(Effects& e) const override { e.*field_ = Field{}; }
    bool enabled(const Effects& e) const override { return (e.*field_).enabled; }
    std::vector<double> values(const Effects& e) const override { return {(e.*field_).*value_}; }

private:
    Field Effects::*field_;
    double Field::*value_;
};

// The struct of one built-in (an unnamed struct in Effects).
#define DW_FIELD(member) decltype(Effects::member)

class ClockOffset final : public OneNumber<DW_FIELD(clock_offset)> {
public:
    ClockOffset() : OneNumber(&Effects::clock_offset, &DW_FIELD(clock_offset)::offset_s) {}
    std::string name() const override { return kClockOffsetEffect; }
    std::vector<EffectParameter> parameters() const override {
        return {{"offset_s", "s", -10, 10, -0.5, 0.5, range(-0.3, 0.3, 25), 0.0}};
    }
    Stage stage() const override { return Stage::clock; }
    double clock_delay_s(const Effects& e) const override { return e.clock_offset.offset_s; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat("**clock_offset** — ", who.clock, " is ", f3(std::abs(v[0])), " s ",
                        v[0] >= 0 ? "behind" : "ahead of",
                        " the poses': the force on the sufferer at pose time t is stamped t ", v[0] >= 0 ? "+ " : "− ",
                        f3(std::abs(v[0])),
                        " s in wrench.csv. Nothing aerodynamic is missing; the two time bases differ. At 0.5 m/s it ",
                        "moves the force pattern ", f3(std::abs(v[0]) * 50, 1), " cm ", who.along,
                        " — while the time shift is the same at every separation (table of shifts). ");
    }
};

class SensorLag final : public OneNumber<DW_FIELD(sensor_lag)> {
public:
    SensorLag() : OneNumber(&Effects::sensor_lag, &DW_FIELD(sensor_lag)::tau_s) {}
    std::string name() const override { return "sensor_lag"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"tau_s", "s", 0, 10, 0.0, 0.5, range(0.0, 0.3, 13), 0.0}};
    }
    Stage stage() const override { return Stage::sensor; }
    void on_sensor(const Effects& e, const std::vector<double>& t, RecordedWrench& series) const override {
        first_order_lag(e.sensor_lag.tau_s, t, series);
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat(
            "**sensor_lag** — ", who.sensor, " is a first-order low-pass of the force with a time constant of ",
            f3(v[0]), " s: peaks are late and flattened. ",
            who.flying ? "The estimate's own dynamics (the thrust model's motor lag, the state estimator's filtering)"
                       : "The stand's dynamics (filtering, mounting)",
            " were left out. ");
    }
};

class WakeTransport final : public OneNumber<DW_FIELD(wake_transport)> {
public:
    WakeTransport() : OneNumber(&Effects::wake_transport, &DW_FIELD(wake_transport)::delay_scale) {}
    std::string name() const override { return "wake_transport"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"delay_scale", "", 0, 10, 0.0, 5.0, range(0.0, 3.0, 7), 1.0}};
    }
    bool changes_flow() const override { return true; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat(
            "**wake_transport** — the downwash takes time to descend: the force follows each neighbour's state ",
            f3(v[0], 2),
            " × τ(s) ago, τ(s) the turbulent jet's descent time over the vertical separation s (146 ms at 1.3 m for ",
            "k = 1). The simulation had the force follow the neighbour instantly. Its signature: the time shift grows "
            "with separation. ");
    }
};

class ForceScale final : public OneNumber<DW_FIELD(force_scale)> {
public:
    ForceScale() : OneNumber(&Effects::force_scale, &DW_FIELD(force_scale)::scale) {}
    std::string name() const override { return "force_scale"; }
    std::vector<EffectParameter> parameters() const override { return {{"scale", "", 0, 10, 0.3, 3.0, {}, 1.0}}; }
    Stage stage() const override { return Stage::calibration; }
    void on_calibration(const Effects& e, Wrench6& w, const Wrench6&) const override {
        for (auto& v : w) v *= e.force_scale.scale;
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat("**force_scale** — the recorded wrench is ", f3(v[0]),
                        " × the simulated one everywhere: a mass, drag coefficient or ",
                        who.flying ? "thrust-model gain" : "load-cell gain", " that differs from the model by ",
                        f3((v[0] - 1) * 100, 1), " %. ");
    }
};

class GroundEffect final : public OneNumber<DW_FIELD(ground_effect)> {
public:
    GroundEffect() : OneNumber(&Effects::ground_effect, &DW_FIELD(ground_effect)::coefficient) {}
    std::string name() const override { return "ground_effect"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", 0, 50, 0.0, 50.0, range(0.0, 20.0, 5), 0.0}};
    }
    bool applies(int, bool flying) const override { return flying; }
    Stage stage() const override { return Stage::sufferer; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat("**ground_effect** — extra lift near the floor: ", f3(v[0], 2),
                        " × the hover thrust × (R / 4h)². ");
    }
};

#undef DW_FIELD

class PositionOffset final : public EffectType {
public:
    std::string name() const override { return "position_offset"; }
    std::vector<EffectParameter> parameters() const override {
        std::vector<EffectParameter> p;
        for (const char* axis : {"offset_n_m", "offset_e_m", "offset_d_m"})
            p.push_back({axis, "m", -10, 10, -0.3, 0.3, {}, 0.0});
        return p;
    }
    bool changes_flow() const override { return true; }
    std::string grouped_key() const override { return "offset_m"; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        e.position_offset = {on, {v[0], v[1], v[2]}};
    }
    void clear(Effects& e) const override { e.position_offset = {}; }
    bool enabled(const Effects& e) const override { return e.position_offset.enabled; }
    std::vector<double> values(const Effects& e) const override {
        return {e.position_offset.offset_m.begin(), e.position_offset.offset_m.end()};
    }
    void keys(KeyVisitor& k, Effects& e) const override {
        k.flag("enabled", e.position_offset.enabled);
        const auto p = parameters().front();  // the three axes share their bounds
        k.numbers(grouped_key(), e.position_offset.offset_m, {p.config_min, p.config_max, "m"},
                  "expected [n, e, d] in metres");
    }
    Stage stage() const override { return Stage::positions; }
    std::array<double, 3> position_error_m(const Effects& e) const override { return e.position_offset.offset_m; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice& who) const override {
        return log::cat(
            "**position_offset** — the neighbours' motion-capture frame is offset from the sufferer's by (", f3(v[0]),
            ", ", f3(v[1]), ", ", f3(v[2]),
            ") m (N, E, D): the force pattern sits off the recorded positions by a fixed distance, the same ",
            who.flying ? "whichever way the neighbour passes" : "on +E and −E legs", ". ");
    }
};

class CellCrosstalk final : public EffectType {
public:
    std::string name() const override { return "cell_crosstalk"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", -1, 1, -0.5, 0.5, {}, 0.0}};
    }
    bool has_axes() const override { return true; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair a) const override {
        e.cell_crosstalk = {on, a.from, a.to, v[0]};
    }
    void clear(Effects& e) const override { e.cell_crosstalk = {}; }
    bool enabled(const Effects& e) const override { return e.cell_crosstalk.enabled; }
    std::vector<double> values(const Effects& e) const override { return {e.cell_crosstalk.coefficient}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        auto& x = e.cell_crosstalk;
        k.flag("enabled", x.enabled);
        k.choice("from", x.from, kAxes, "axis");
        k.choice("to", x.to, kAxes, "axis");
        const auto p = parameters().front();
        k.number(p.name, x.coefficient, {p.config_min, p.config_max});
    }
    Stage stage() const override { return Stage::calibration; }
    // The leak is of the true `from` axis, which the recording holds (crosstalk leaves it alone).
    void on_calibration(const Effects& e, Wrench6& w, const Wrench6& recorded) const override {
        const auto& x = e.cell_crosstalk;
        w[static_cast<std::size_t>(x.to)] += x.coefficient * recorded[static_cast<std::size_t>(x.from)];
    }
    std::string describe(const std::vector<double>& v, AxisPair a, const EffectVoice& who) const override {
        return log::cat("**cell_crosstalk** — ", who.flying ? "the force estimate" : "the stand's calibration",
                        " leaks ", kAxes[a.from], " into ", kAxes[a.to], ": ", f3(v[0] * 100, 2), " % of the true ",
                        kAxes[a.from], " appears on ", kAxes[a.to], ". ",
                        who.flying
                            ? "A flying sufferer has no load cells: this stands for a force that follows another axis "
                              "(the vehicle tilting as it is pushed, or the thrust direction misestimated). "
                            : "Recalibrate the stand (dw-stand-agent calibrate). ");
    }
};

class JetMerging final : public EffectType {
public:
    std::string name() const override { return "jet_merging"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"contraction", "", 0.05, 2, 0.05, 1.0, range(0.2, 1.0, 5), 0.8}};
    }
    bool changes_flow() const override { return true; }
    bool applies(int neighbours, bool) const override { return neighbours >= 2; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        e.jet_merging.enabled = on;
        e.jet_merging.contraction = v[0];
    }
    void clear(Effects& e) const override { e.jet_merging = {}; }
    bool enabled(const Effects& e) const override { return e.jet_merging.enabled; }
    std::vector<double> values(const Effects& e) const override { return {e.jet_merging.contraction}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        EffectType::keys(k, e);
        k.number("onset", e.jet_merging.onset, {0, 10});
        k.number("full", e.jet_merging.full, {0, 10});
        k.require(e.jet_merging.full > e.jet_merging.onset, "full", "must be greater than onset");
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat(
            "**jet_merging** — neighbouring jets merge into one contracted, momentum-conserving column where their "
            "half-widths overlap (contraction ",
            f3(v[0], 2), "): the aggregate is not the sum of single jets. It acts only with ",
            "two or more neighbours close together and far enough above the sufferer for the jets to widen. ");
    }
};

class FloorRecirculation final : public EffectType {
public:
    std::string name() const override { return "floor_recirculation"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", 0, 1, 0.0, 0.3, range(0.0, 0.1, 5), 0.02}};
    }
    bool changes_flow() const override { return true; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        e.floor_recirculation.enabled = on;
        e.floor_recirculation.coefficient = v[0];
    }
    void clear(Effects& e) const override { e.floor_recirculation = {}; }
    bool enabled(const Effects& e) const override { return e.floor_recirculation.enabled; }
    std::vector<double> values(const Effects& e) const override { return {e.floor_recirculation.coefficient}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        EffectType::keys(k, e);
        k.number("length_m", e.floor_recirculation.length_m, {0.01, 100});
    }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat(
            "**floor_recirculation** — jets hitting the floor come back as a bias that grows with the jets impinging "
            "(coefficient ",
            f3(v[0]), "). ");
    }
};

class BodyDrag final : public EffectType {
public:
    std::string name() const override { return "body_drag"; }
    std::vector<EffectParameter> parameters() const override {
        return {{"cda_h_m2", "m²", 0, 10, 0.0, 0.1, {}, 0.0}, {"cda_v_m2", "m²", 0, 10, 0.0, 0.1, {}, 0.0}};
    }
    bool applies(int, bool flying) const override { return flying; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair) const override {
        e.body_drag = {on, v[0], v[1]};
    }
    void clear(Effects& e) const override { e.body_drag = {}; }
    bool enabled(const Effects& e) const override { return e.body_drag.enabled; }
    std::vector<double> values(const Effects& e) const override { return {e.body_drag.cda_h_m2, e.body_drag.cda_v_m2}; }
    Stage stage() const override { return Stage::sufferer; }
    std::string describe(const std::vector<double>& v, AxisPair, const EffectVoice&) const override {
        return log::cat("**body_drag** — the flying sufferer's own drag against its motion through still air: C_d A = ",
                        f3(v[0], 4), " m² horizontally, ", f3(v[1], 4),
                        " m² vertically (f = −½ ρ C_d A |v| v). The simulation had only the neighbours' air. ");
    }
};

}  // namespace

std::vector<std::unique_ptr<EffectType>> builtin_effects() {
    std::vector<std::unique_ptr<EffectType>> v;
    v.push_back(std::make_unique<ClockOffset>());
    v.push_back(std::make_unique<SensorLag>());
    v.push_back(std::make_unique<WakeTransport>());
    v.push_back(std::make_unique<PositionOffset>());
    v.push_back(std::make_unique<ForceScale>());
    v.push_back(std::make_unique<CellCrosstalk>());
    v.push_back(std::make_unique<JetMerging>());
    v.push_back(std::make_unique<FloorRecirculation>());
    v.push_back(std::make_unique<BodyDrag>());
    v.push_back(std::make_unique<GroundEffect>());
    return v;
}

}  // namespace dw::physics
