#pragma once
// The effect vocabulary (../shared/FLIGHT_FORMAT.md) as types, registered once. Each effect says
// its name, its parameters (units, what a configuration may say, what the explainer searches),
// where it acts, how it is switched on in a configuration, its YAML section and its paragraph in
// the report. The configuration, the simulator, the replay, the explainer and the report iterate
// the registry; none of them compares effect names.
//
// Each effect acts at one stage of the recording chain (physics/recording_chain.hpp), which the
// simulator, the explainer's resimulation and dw-stand-agent --sim share: the built-ins
// (effects/, one file each) through the hooks below, one discretisation each; the flow's in
// wrench_model, where the air is evaluated. An effect added in a file of its own keeps its values in Effects::extra and acts
// through on_recording, after the tare: adding such an effect is that one file and its tests.
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <string>
#include <vector>

#include "core/keys.hpp"
#include "physics/config.hpp"

namespace dw::physics {

// Effects that explain the same change of the recording against the poses, which a flight may be
// unable to separate: when the explainer cannot tell its members apart it names the family and what
// they share, never one member alone. Each effect type says which family it belongs to.
struct EffectFamily {
    const char* name;
    const char* shared;  // in the report's words
    const char* unit;    // after the shared quantity's value
};
inline constexpr EffectFamily kDelayFamily{"delay", "a delay between force and pose", " s (the located shift)"};
// A gain of the whole push, and jets that do not add as forces: both make the push a multiple of
// the single jets' sum wherever jets share it; a gain shows alone only where one jet pushes alone.
inline constexpr EffectFamily kPushFamily{"push", "a push", " × the sum of the single jets' pushes"};

struct EffectParameter {
    std::string name, unit;
    double config_min = 0, config_max = 0;  // what a configuration may say
    double fit_min = 0, fit_max = 0;        // what the explainer searches
    std::vector<double> grid;               // the explainer's starting points before the local fit (may be empty)
    double start = 0;                       // the neutral value (the effect absent)
};

// The axes of an effect between two axes (0-5, flight::kAxes), chosen before the fit.
struct AxisPair {
    int from = 2, to = 0;
    bool operator==(const AxisPair&) const = default;
};

// Who measured the force, in the report's words: a load stand, or a flying sufferer's estimate.
struct EffectVoice {
    bool flying = false;
    std::string sensor, clock, along;  // "the stand", "the stand's clock", where the force pattern moves
};

// How `dw-explain coverage` checks the explainer's intervals on an effect: simulated flights in
// this formation, each parameter's hidden value drawn uniformly from its range (an effect between
// two axes: these).
struct CoverageCase {
    std::string formation;
    std::vector<std::pair<double, double>> hidden;
    AxisPair axes{};
};

// How `dw-explain proof` shows the explainer finds an effect: one simulated flight in this
// formation (this seed) with the effect hidden at these values (an effect between two axes: these).
struct ProofCase {
    std::string formation, description;
    std::vector<double> values;
    AxisPair axes{};
    std::uint64_t seed = 1;
};

// How the real-data proofs (dw-explain real-proof, session-proof) conceal an effect of the rig in
// recorded flights, where nobody knows the physics: the option that sets its size and what it may
// say, the sizes, and how the concealed value combines with what the untouched flight shows of it.
struct RealConcealment {
    std::string option, option_help;      // "--clock", "the wrench stamped this late [s]"
    Range range;                          // what the option may say
    double single = 0;                    // one flight's proof: a size the shared flights can show
    double session = 0;                   // a session's: below what one flight alone shows
    bool multiplies = false;              // the truth: the flight's own value × the size (else +)
    AxisPair axes{};                      // between these axes (an effect with axes)
    std::string said_before, said_after;  // the case in words: said_before + size + said_after
};

// What a flow effect sees of the air at the sufferer, and a jet it regroups with its weight
// (physics/wrench_model.hpp).
struct AirScene;
struct WeightedProducer;

using flight::Wrench6;
using RecordedWrench = std::vector<Wrench6>;

// The recording chain's stages, in its order: the positions the motion capture reports, the air
// the neighbours make, the sufferer's own forces, the sensor's response, the stand's calibration
// (after the tare), the stamps' clock, and the recorded wrench as written.
enum class Stage { positions, air, sufferer, sensor, calibration, clock, recording };
inline constexpr std::size_t kStages = static_cast<std::size_t>(Stage::recording) + 1;

// What an effect on a flying sufferer's own forces sees of it (stage sufferer): NED, SI.
struct SuffererState {
    std::array<double, 3> position_m{}, velocity_m_s{};
    double hover_thrust_n = 0, prop_radius_m = 0, air_density_kg_m3 = 0;
};

class EffectType {
public:
    virtual ~EffectType() = default;
    virtual std::string name() const = 0;
    // A built-in's place in the vocabulary (../shared/FLIGHT_FORMAT.md): the registry's order.
    virtual int vocabulary_place() const { return 0; }
    virtual std::vector<EffectParameter> parameters() const = 0;
    // Whether evaluating it needs the air again, or only the recording's view of it.
    virtual bool changes_flow() const { return false; }
    // Whether it can act in a flight with this many neighbours and this kind of sufferer.
    virtual bool applies(int neighbours, bool flying) const;
    // Whether, on, it acts on the sufferer far from every jet too (a flow effect), so that no
    // sample's air can be left out as too far from the neighbours.
    virtual bool acts_far_from_jets() const { return false; }
    // Whether it acts between two axes chosen before the fit (AxisPair).
    virtual bool has_axes() const { return false; }
    // The family of effects it may be indistinguishable from (nullptr: none).
    virtual const EffectFamily* family() const { return nullptr; }
    // Its parameters for the family's shared quantity (the delay family's: the shift between force
    // and pose, s), where one reading of it is this effect's; the explainer starts its fit there too.
    virtual std::optional<std::vector<double>> from_family_quantity(double) const { return std::nullopt; }
    // Whether it is a gain of the whole push, told from the rest of its family only on samples where
    // one jet pushes alone (its value is then the family's shared quantity).
    virtual bool gain_of_the_push() const { return false; }
    // The report's JSON gives the parameters as one array under this key ("" : one key each).
    virtual std::string grouped_key() const { return ""; }

    // The configuration: on or off with these values (and axes) kept; on; off and back to its
    // defaults; whether on; the values it holds.
    virtual void store(Effects& e, bool on, const std::vector<double>& values, AxisPair axes) const;
    void set(Effects& e, const std::vector<double>& values, AxisPair axes = {}) const;
    // On, with the values (and axes) it holds (a configuration's, else its defaults).
    void switch_on(Effects& e) const { store(e, true, values(e), axes(e)); }
    virtual void clear(Effects& e) const;
    virtual bool enabled(const Effects& e) const;
    virtual std::vector<double> values(const Effects& e) const;
    // The axes it holds (an effect with axes; else the default pair).
    virtual AxisPair axes(const Effects&) const { return {}; }
    // The keys of its section `effects.<name>`, declared once for reading and writing
    // (core/keys.hpp): by default `enabled` and each parameter by name.
    virtual void keys(KeyVisitor& k, Effects& e) const;

    // Where in the recording chain it acts (default: the air when it changes the flow, else the
    // recorded wrench).
    virtual Stage stage() const { return changes_flow() ? Stage::air : Stage::recording; }
    // The chain's hooks, each called only at the effect's own stage while it is on:
    // positions: how far the motion capture's positions are off the truth (NED, m).
    virtual std::array<double, 3> position_error_m(const Effects&) const { return {0, 0, 0}; }
    // air (a flow effect, evaluated where the wrench model evaluates the jets): a wrench of its own
    // beyond the jets' (NED, N and N·m); the jets' transport delay, × each jet's descent time (0:
    // none); whether it regroups the jets, and then the jets whose air adds as the aggregation
    // says, each with its weight (in this order: a flow is summed in it).
    virtual Wrench6 air_wrench(const Effects&, const AirScene&) const { return {}; }
    virtual double transport_delay_scale(const Effects&) const { return 0; }
    virtual bool regroups_jets() const { return false; }
    virtual void regroup_jets(const Effects&, const AirScene&, std::vector<WeightedProducer>&) const {}
    // sufferer: the force a flying sufferer's own motion adds to what it feels (NED, N).
    virtual Wrench6 sufferer_force(const Effects&, const SuffererState&) const { return {}; }
    // sensor: one step of the sensor's response: over dt seconds the force on the sufferer went
    // (linearly) from x0 to x1 and the reading from y, which becomes the reading at the step's end.
    // One recurrence for a whole series and for a live stream (RecordingChain).
    virtual void sensor_step(const Effects&, double dt, const Wrench6& x0, const Wrench6& x1, Wrench6& y) const;
    // calibration: one calibrated sample after the tare; `recorded` is the recording's own value of
    // that sample (while simulating, w itself as the earlier effects left it).
    virtual void on_calibration(const Effects&, Wrench6& w, const Wrench6& recorded) const;
    // clock: how late the wrench's stamps run against the poses' (s).
    virtual double clock_delay_s(const Effects&) const { return 0; }
    // recording: the change to the recorded wrench (stamps in s), given the effect's values.
    virtual void on_recording(const std::vector<double>& values, const std::vector<double>& stamps,
                              RecordedWrench& w) const;
    // Its proof case; none for an effect that the simulated flights over a stand cannot show.
    virtual std::optional<ProofCase> proof_case() const { return std::nullopt; }
    // Its coverage case; none for an effect that the simulated flights over a stand cannot show.
    virtual std::optional<CoverageCase> coverage_case() const { return std::nullopt; }
    // Its values in the proof's flight with two effects hidden at once; none: not one of them.
    virtual std::optional<std::vector<double>> in_two_effects_case() const { return std::nullopt; }
    // Its concealment on recorded flights; none for an effect the recording chain cannot put into a
    // recording after the fact (the air's, the sufferer's, the positions').
    virtual std::optional<RealConcealment> real_concealment() const { return std::nullopt; }
    // Its paragraph in the report (without the held-out numbers, which the report adds).
    virtual std::string describe(const std::vector<double>& values, AxisPair axes, const EffectVoice& who) const = 0;

    std::vector<double> neutral() const;
    // What it does in e: its values where it is on, else its neutral ones.
    std::vector<double> in_force(const Effects& e) const { return enabled(e) ? values(e) : neutral(); }
};

// Whether an effect belongs to the rig's measurement chain — it acts after the air has reached the
// sufferer (the sensor's response, the calibration, the stamps' clock), so it is the same hardware
// on every flight a lab flies with it, and a session of flights shares one value of it. The air's,
// the sufferer's and the positions' effects depend on where and how each flight flew.
inline bool of_the_rig(const EffectType& t) {
    return t.stage() == Stage::sensor || t.stage() == Stage::calibration || t.stage() == Stage::clock;
}

// Every registered effect, built-ins first in the vocabulary's order, then those of the effect
// modules (below). Throws dw::InputError naming a module that cannot be loaded.
const std::vector<const EffectType*>& effect_types();

// A lab's own effects without rebuilding the programs: shared libraries named in this environment
// variable (paths, colon-separated), each registering its effects when it is loaded (a static
// EffectRegistration in its one file, as tests/toy_effect.cpp does; built as a MODULE library
// against the lab's headers). Loaded on the registry's first use; every program that reads a
// physics configuration then knows them.
inline constexpr const char* kEffectModulesVariable = "DW_EFFECT_MODULES";
// The effect of the stamps' clock (the first at Stage::clock), which the lab's time service
// measures live (dds/clock_sync.hpp): the explainer's locator shifts it, its report sets the
// measurement beside it. A program error (std::logic_error) if no effect acts there.
const EffectType& clock_effect();
// The named effect; throws dw::InputError "<what>: unknown effect 'x' (expected one of ...)".
const EffectType& effect_type(const std::string& name, const std::string& what = "effect");
// The known names, comma separated (for messages).
std::string effect_names();
// Adds an effect (at start-up: a static EffectRegistration in the effect's own file). Throws
// std::logic_error for a name already registered.
void register_effect(std::unique_ptr<EffectType> type);
template <class T>
struct EffectRegistration {
    EffectRegistration() { register_effect(std::make_unique<T>()); }
};

// The built-ins, in the vocabulary's order: each file in effects/ is one, with its factory
// make_<file name>() (physics/CMakeLists.txt lists them from the folder).
std::vector<std::unique_ptr<EffectType>> builtin_effects();

}  // namespace dw::physics
