// cell_crosstalk: one axis of the calibration leaking into another (stage: calibration).
#include <cmath>

#include "flight/flight.hpp"
#include "physics/effects/common.hpp"

namespace dw::physics::effects {
namespace {

using flight::kAxes;

struct CellCrosstalkSettings {
    bool enabled = false;
    int from = 2, to = 0;  // axes 0-5
    double coefficient = 0.0;
};

class CellCrosstalk final : public BuiltIn<CellCrosstalkSettings> {
public:
    CellCrosstalk() : BuiltIn("cell_crosstalk") {}
    int vocabulary_place() const override { return 6; }  // ../shared/FLIGHT_FORMAT.md
    std::vector<EffectParameter> parameters() const override {
        return {{"coefficient", "", -1, 1, -0.5, 0.5, {}, 0.0}};
    }
    bool has_axes() const override { return true; }
    void store(Effects& e, bool on, const std::vector<double>& v, AxisPair a) const override {
        of(e) = {on, a.from, a.to, v[0]};
    }
    std::vector<double> values(const Effects& e) const override { return {of(e).coefficient}; }
    AxisPair axes(const Effects& e) const override { return {of(e).from, of(e).to}; }
    void keys(KeyVisitor& k, Effects& e) const override {
        auto& x = of(e);
        k.flag("enabled", x.enabled);
        k.choice("from", x.from, kAxes, "axis");
        k.choice("to", x.to, kAxes, "axis");
        const auto p = parameters().front();
        k.number(p.name, x.coefficient, {p.config_min, p.config_max});
    }
    Stage stage() const override { return Stage::calibration; }
    // The leak is of the true `from` axis, which the recording holds (crosstalk leaves it alone).
    void on_calibration(const Effects& e, Wrench6& w, const Wrench6& recorded) const override {
        const auto& x = of(e);
        w[static_cast<std::size_t>(x.to)] += x.coefficient * recorded[static_cast<std::size_t>(x.from)];
    }
    std::optional<ProofCase> proof_case() const override {
        return ProofCase{"single", "crosstalk f_d -> f_e, 4 %", {0.04}, {2, 1}, 15};
    }
    std::optional<CoverageCase> coverage_case() const override {
        return CoverageCase{"single", {{-0.06, 0.06}}, {2, 1}};
    }                                                                   // f_d leaks into f_e
    std::optional<RealConcealment> real_concealment() const override {  // f_d leaks into f_n
        return RealConcealment{"--leak", "f_n += leak x f_d", {-1, 1}, 0.113, 0.09, false, {2, 0}, "f_n += ", " f_d"};
    }
    std::string describe(const std::vector<double>& v, AxisPair a, const EffectVoice& who) const override {
        return log::cat("**cell_crosstalk** — ", who.flying ? "the force estimate" : "the stand's calibration",
                        " leaks ", kAxes[a.from], " into ", kAxes[a.to], ": ", fixed(v[0] * 100, 2), " % of the true ",
                        kAxes[a.from], " appears on ", kAxes[a.to], ". ",
                        who.flying
                            ? "A flying sufferer has no load cells: this stands for a force that follows another axis "
                              "(the vehicle tilting as it is pushed, or the thrust direction misestimated). "
                            : "Recalibrate the stand (dw-stand-agent calibrate). ");
    }
};

}  // namespace

std::unique_ptr<EffectType> make_cell_crosstalk() { return std::make_unique<CellCrosstalk>(); }

}  // namespace dw::physics::effects
