#pragma once
// Calibration: a lab's physics fitted to its own vehicles once, on many flights, and validated on
// whole trials it did not see. Per vehicle class (vehicles with the same meta.json parameters):
// as a producer, its jet's strength, width and origin (the far-wake law's three coefficients);
// as a sufferer, its rotors' thrust loss in oncoming flow. Fitted jointly over every flight by
// Levenberg-Marquardt on f_d where a neighbour is near; each trial is left out in turn and
// predicted by the fit on the others (held-out error before/after per trial); the intervals are
// the leave-one-trial-out jackknife's. Writes a physics file (the base with the classes) and a
// report (calibration.md/.json, pictures).
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

#include "core/numbers.hpp"
#include "flight/flight.hpp"
#include "physics/config.hpp"

namespace dw::analysis {

struct CalibrateOptions {
    std::vector<std::string> flights;  // flight folders
    physics::PhysicsConfig physics;    // the base: what is not calibrated, and the starting values
    std::string out_dir;
    int jobs = 2;             // flights replayed at once
    int stride = 2;           // every stride-th near sample enters the fit (all enter the errors)
    int max_iterations = 30;  // Levenberg-Marquardt iterations of the fit on every trial
    int fold_iterations = 8;  // ... of each leave-one-trial-out fit (started from the full fit)
    // Also explain each trial's flights against the calibration that left the trial out (its report
    // under folds/<trial>/): what is left once the lab's physics is calibrated.
    bool explain_heldout = false;
    std::function<void(const std::string&)> progress;
    std::stop_token stop;
};
inline constexpr Range kStrideRange{1, 100};
inline constexpr Range kIterationsRange{1, 500};

// One calibrated parameter of one class: its value on every trial and its 95 % interval.
struct CalibratedParameter {
    std::string vehicle_class, name, unit;
    double start = 0, value = 0, lo = 0, hi = 0;
};

// One trial's f_d error where a neighbour is near: the base physics, the fit on every trial and the
// fit without this trial (held out).
struct TrialError {
    std::string trial, pairing;  // e.g. "swap_ss cf50_01+cf51_01", "32 g under 67 g"
    std::vector<std::string> flights;
    std::size_t samples = 0;
    double rmse_before = 0, rmse_all = 0, rmse_heldout = 0;
    // The jets' turbulence intensity of the calibration without this trial, measured on the residual
    // it leaves on the other trials (0: the spread does not grow there, and the fold keeps the base's
    // turbulence): what explain_heldout's explanation counts as noise where a jet pushes.
    double turbulence_intensity = 0;
    // The noise model of the calibration without this trial (physics/prediction_noise.hpp), fitted
    // by maximum likelihood on the residual it leaves on the other trials.
    physics::PredictionNoise noise;
    // The held-out residual standardised by that noise model (each sample over
    // sqrt(floor² + (s p)² + (tau dp/dt)²): its flight's noise floor, the push predicted and its
    // rate), its RMS: 1 when the physics and the noise model hold; kStandardisedBand says how near counts.
    double z_rms_heldout = 0;
    // With explain_heldout, per flight: the explainer's held-out f_d error after its fit over its
    // noise floor, and what it accepted.
    std::vector<double> explained_ratio;
    std::vector<double> discrepancy_ratio;  // ... and with the learnt discrepancy (analysis/discrepancy.hpp)
    std::vector<std::vector<std::string>> explained_by;
};

// A trial whose standardised held-out RMS lies within this band is predicted to its noise (issue 71).
inline constexpr Range kStandardisedBand{0.8, 1.25};

// A flight with nobody near the sufferer (a vehicle flying alone): no downwash to calibrate on, so
// it takes no part in the fit, but the residual's own errors show there. Its f_d mean and RMS, and
// their least-squares line against the sufferer's own vertical velocity (NED: + descending).
struct AloneFlight {
    std::string flight, vehicle_class;
    std::size_t samples = 0;
    double mean_f_d = 0, rms_f_d = 0, sd_f_d = 0;
    double slope_per_v_d = 0;   // N per m/s
    double rms_after_line = 0;  // f_d's RMS once that line is taken away
    // The explainer's noise floor where nobody is ever far (a swap's): successive differences'
    // spread. sd_f_d over it is what a model exact on every sample (and on the residual's zero)
    // would leave there, in such floors: the residual's own slow error, beyond its jitter.
    double floor_differences = 0;
    double exact_model_ratio() const { return sd_f_d / floor_differences; }
};
// Only the samples this high above the floor count: flights alone may fly low and touch the floor
// (the Neural-Swarm ones did, with onboard ground-effect compensation: below 0.2 m their f_d
// spreads three times wider), where the flights under neighbours do not go.
inline constexpr double kAloneMinHeight_m = 0.3;
AloneFlight measure_alone(const flight::Flight& f, const std::string& dir, const std::string& vehicle_class);

struct CalibrateResult {
    physics::PhysicsConfig calibrated;
    std::vector<CalibratedParameter> parameters;
    std::vector<TrialError> trials;
    std::vector<AloneFlight> alone;
    // The jets' turbulence intensity: half the slope 2I of the residual's spread against the
    // calibrated push, pooled over every pairing (calibration_report.hpp, Scatter); written into
    // the calibrated physics (turbulence enabled) when the spread grows with the push.
    double turbulence_intensity = 0;
    std::string physics_path, report_path;  // in --out, once it is complete
    double seconds = 0;
};

// Throws dw::InputError for a flight that cannot be read or calibrated on (named), or when the
// flights hold fewer than two trials (nothing to leave out).
// What calibrate() writes in --out (with calibration.json, the pictures and folds/), all together
// or, on a failure or a stop, nothing.
inline constexpr const char* kCalibratedPhysicsFile = "physics.yaml";
inline constexpr const char* kCalibrationReportFile = "calibration.md";
CalibrateResult calibrate(const CalibrateOptions& o);

}  // namespace dw::analysis
