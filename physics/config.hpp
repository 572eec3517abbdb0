#pragma once
// The physics configuration (downwash-physics/1): which jet model and aggregation law, the
// vehicles, the stand, noise and turbulence, and the switchable effects named as in
// ../shared/FLIGHT_FORMAT.md. Loaded strictly from YAML: an unknown key or a bad value is an
// error naming file, line and key. config/physics.example.yaml documents every key.
#include <any>
#include <array>
#include <string>
#include <map>
#include <vector>

#include "core/keys.hpp"
#include "core/numbers.hpp"
#include "flight/flight.hpp"

namespace dw::physics {

inline constexpr Range kCellNoiseRange{0, 10, "N"};  // load-cell noise, 1 sigma

enum class JetModelKind { bauersfeld, jain };
inline constexpr std::array<const char*, 2> kJetModelNames = {"bauersfeld", "jain"};  // JetModelKind's order
enum class Aggregation { force_sum, velocity_superposition };
inline constexpr std::array<const char*, 2> kAggregationNames = {"force_sum",
                                                                 "velocity_superposition"};  // Aggregation's order

// One definition with the flight format's (meta.json's vehicles).
using VehicleParams = flight::VehicleInfo;

struct JainParams {  // Jain et al., ICUAS 2019; published constants disagree: fit them
    double c_ax = 5.0;
    double c_rad = 10.0;
    double z0_m = 0.25;
    double diameter_m = 0.25;
};

// The far-wake jet law's three coefficients (Bauersfeld et al.; ../shared/PHYSICS.md), fitted
// there to larger vehicles: U_c = U_H strength / (s/l + origin), r_half = width (s/l + origin) l.
// A lab calibrates them per vehicle class (VehicleClass, dw-explain calibrate).
struct JetCoefficients {
    double strength = 10.11;
    double origin = 5.817;
    double width = 0.07668;
};

struct SuffererParams {
    VehicleParams vehicle;
    double drag_coefficient = 1.18;         // flat plate, vertical flow
    double lateral_drag_coefficient = 0.3;  // edge-on, horizontal flow
    double arm_width_m = 0.02;
    double body_size_m = 0.08;
    int disc_rings = 2;  // planform resolution per rotor disc
    int disc_sectors = 6;
    bool thrust_loss = true;          // rotors lose thrust in oncoming flow
    double kv_omega_n_per_mps = 0.1;  // per rotor
    // In-plane rotor drag (H-force): per rotor, newtons per m/s of lateral air through its disc.
    // Only the jets' turbulent lateral velocity drives it (lateral buffeting); the mean flow's
    // lateral push is the bluff-body term above.
    double rotor_drag_n_per_mps = 0.03;
};

struct StandParams {
    double height_m = 1.4;                 // sufferer above the floor
    double lateral_radius_m = 0.1;         // lateral cells' distance from the centre
    double counts_per_newton = 21400.0;    // 10 kg cell, 1 mV/V, HX711 gain 128
    double offset_sigma_counts = 50000.0;  // per-chip zero offsets (removed by the tare)
    double rate_hz = 80.0;
    double rate_skew = 0.01;  // each chip's rate within ±1 %
    double noise_n = 0.025;   // per cell, 1 sigma
    double tare_s = 1.0;      // averaging time of the tare at the start
};

inline constexpr double kLateralIntensity = 0.2;  // v'/U of a round jet (Pope, Turbulent Flows)

inline constexpr Range kTurbulenceIntensityRange{0, 1};  // u'/U

struct TurbulenceParams {
    bool enabled = true;
    double intensity = 0.1;       // u'/U of the jet speed (Ornstein-Uhlenbeck)
    double time_scale_s = 0.025;  // ≈ r_half / U_c
    // Lateral buffeting: each jet's lateral velocity fluctuation, v'/U of its local axial speed,
    // per horizontal axis, with its own correlation time (Ornstein-Uhlenbeck). Off by default:
    // kLateralIntensity is the physical value (README: why it is not the default yet).
    double lateral_intensity = 0.0;
    double lateral_time_scale_s = 0.03;
};

// A prediction's noise model beyond the flight's floor (physics/prediction_noise.hpp): a scatter
// that grows with the push p (push_share × p: the jets' turbulence, 2 I, and what the mean-flow
// model leaves near a jet) and one that grows with how fast the push changes (timing_spread_s × dp/dt:
// when a wake arrives varies). dw-explain calibrate fits both by maximum likelihood on the trials it
// calibrates on; push_share 0 (not calibrated): 2 I from the turbulence, and no timing term.
struct PredictionNoise {
    double push_share = 0;
    double timing_spread_s = 0;
};
inline constexpr Range kPushShareRange{0, 5};
inline constexpr Range kTimingSpreadRange_s{0, 1, "s"};

struct DynamicsParams {  // simulated vehicles
    double natural_frequency_rad_s = 3.0;
    double damping = 0.6;
    double hover_noise_m = 0.02;
    double hover_noise_time_s = 1.0;
    double rate_hz = 360.0;  // integration rate (also the wrench model's rate)
};

struct MocapParams {
    double rate_hz = 180.0;
    double noise_m = 0.0005;
};

struct Effects {
    // The built-ins' settings, each its own file's struct (physics/effects/common.hpp, SettingsOf),
    // by name; an effect absent here has its defaults.
    std::map<std::string, std::any> settings;
    // Effects registered beyond these (physics/effect_types.hpp): those switched on, with their values.
    std::map<std::string, std::vector<double>> extra;
};

// A vehicle class's own physics, calibrated on its flights (dw-explain calibrate): a vehicle whose
// parameters (meta.json's, else the configuration's) match `vehicle` produces a jet with these
// coefficients and, as the sufferer, feels the flow with this drag and thrust loss.
struct VehicleClass {
    std::string name;
    VehicleParams vehicle;
    JetCoefficients jet;
    double drag_coefficient = 1.18;
    double kv_omega_n_per_mps = 0.1;
    // As the sufferer, its measured f_d's spread (1 sigma) where nobody is near: the noise a right
    // prediction's interval starts from (predictor/intervals.hpp). dw-explain calibrate measures it
    // on the class's flights; 0: not measured.
    double noise_floor_n = 0;
};
inline constexpr Range kNoiseFloorRange{0, 10, "N"};

// A learnt discrepancy carried in a fitted physics file (dw-explain writes it; analysis/discrepancy.hpp
// defines its inputs and evaluates it; dw-sim fly and replay add it to the recorded wrench). It is
// not physics this library computes: a correction to the recorded wrench, linear in inputs the
// analysis derives from a flight — the neighbours' geometry, the sufferer's motion, time and the
// model's own prediction — with the frame those inputs were scaled in when it was learnt.
struct LearntDiscrepancy {
    std::string flight;                // where it was learnt (free text)
    std::vector<double> coefficients;  // rows: the six axes; columns: the inputs, in analysis's order
    std::size_t rows = 0, inputs = 0;
    double height_lo_m = 0, height_step_m = 0, height_width_m = 1;  // the geometry's height bumps
    double t0_s = 0, t1_s = 0;                                      // the flight's time, for the drift
    int drift_bumps = 0;
    double push_top = 1;                            // the push that counts as 1 (noise floors)
    std::array<double, 6> sigma{1, 1, 1, 1, 1, 1};  // the noise floors the push is measured in
    double heldout_gain = 0;  // on the flight it was learnt on, cross-validated: the best axis's share removed
};

struct PhysicsConfig {
    double air_density_kg_m3 = 1.225;
    double gravity_m_s2 = 9.81;
    JetModelKind jet_model = JetModelKind::bauersfeld;
    bool radial_inflow = true;  // entrainment flow from continuity
    JainParams jain;
    JetCoefficients bauersfeld;  // every vehicle's that no class matches
    Aggregation aggregation = Aggregation::force_sum;
    SuffererParams sufferer;
    VehicleParams neighbour;  // neighbours' parameters
    StandParams stand;
    TurbulenceParams turbulence;
    PredictionNoise prediction_noise;
    DynamicsParams dynamics;
    MocapParams mocap;
    Effects effects;
    std::vector<VehicleClass> classes;
    std::string calibration;                     // where the classes came from (the calibration's own line), "" if none
    std::vector<LearntDiscrepancy> discrepancy;  // none, or the one dw-explain learnt
};

// The class whose vehicle parameters v matches (each within 1e-6 relative), or nullptr.
const VehicleClass* class_of(const PhysicsConfig& c, const VehicleParams& v);
// The jet coefficients of vehicle v: its class's, else the configuration's.
JetCoefficients jet_coefficients(const PhysicsConfig& c, const VehicleParams& v);
// c's sufferer flown as vehicle v: v's parameters with its class's drag and thrust loss.
SuffererParams sufferer_as(const PhysicsConfig& c, const VehicleParams& v);

// Throws dw::InputError "file:line:col: key: problem".
PhysicsConfig load_physics(const std::string& path);
// load_physics(path), or the documented defaults (config/physics.example.yaml) when path is empty.
PhysicsConfig physics_or_defaults(const std::string& path);
PhysicsConfig parse_physics(const std::string& yaml, const std::string& name);
// A complete YAML document that parse_physics reads back to the same configuration.
std::string to_yaml(const PhysicsConfig& c);
// Every value of c, exactly (core/keys.hpp): a cache's key for what a configuration computes.
KeyValues key_values(const PhysicsConfig& c);
KeyValues key_values(PhysicsConfig& c);  // the same, of a configuration the caller lets it visit (c is only read)

int axis_index(const std::string& name);  // "f_n" -> 0 ... "m_yaw" -> 5, -1 if unknown

}  // namespace dw::physics
