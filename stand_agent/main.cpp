// dw-stand-agent: eight HX711 load-cell ADCs to a calibrated 6-DOF wrench at 80 Hz.
#include <iostream>
#include <sstream>

#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "physics/config.hpp"
#include "stand_agent/emulated_bank.hpp"
#include "stand_agent/gpiod_lines.hpp"
#include "stand_agent/runner.hpp"

namespace {

std::vector<unsigned> parse_lines(const std::string& text) {
    std::vector<unsigned> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        char* end = nullptr;
        const long v = std::strtol(item.c_str(), &end, 10);
        if (item.empty() || *end != '\0' || !dw::stand::kLineOffsetRange.contains(static_cast<double>(v))) {
            throw dw::InputError("--data-lines: '" + item + "' is not a line number " +
                                 dw::stand::kLineOffsetRange.describe());
        }
        out.push_back(static_cast<unsigned>(v));
    }
    if (out.size() != dw::stand::kChips)
        throw dw::InputError("--data-lines: expected 8 line numbers, got " + std::to_string(out.size()));
    return out;
}

// The emulated HX711 bank, driven by the physics and the mocap topic.
std::unique_ptr<dw::stand::Hx711Lines> emulated_lines(dw::stand::PhysicsSource& source,
                                                      const dw::physics::PhysicsConfig& physics, double noise_n) {
    dw::stand::BankOptions bopt;
    bopt.rate_hz = physics.stand.rate_hz;
    bopt.rate_skew = physics.stand.rate_skew;
    bopt.counts_per_newton = physics.stand.counts_per_newton;
    bopt.offset_sigma_counts = physics.stand.offset_sigma_counts;
    bopt.noise_counts = noise_n * physics.stand.counts_per_newton;
    auto* src = &source;
    return std::make_unique<dw::stand::EmulatedBank>(dw::SystemClock::instance(), bopt,
                                                     [src](int chip, dw::Nanos t) { return src->force(chip, t); });
}

// The calibration --calibration names, else the nominal one of a stand with these parameters.
dw::stand::Calibration calibration_of(const std::string& path, const dw::physics::StandParams& stand) {
    return path.empty() ? dw::stand::Calibration::nominal(stand) : dw::stand::Calibration::load(path);
}

// `dw-stand-agent run`: sample the cells (real, or an emulated bank under --sim) and publish.
struct RunCommand final : dw::cli::Command {
    explicit RunCommand(const dw::dds::ProcessCli& c) : cli(c) {}
    const dw::dds::ProcessCli& cli;
    bool sim = false, realtime = false;
    std::string calibration_path, physics_path, gpio_chip = "gpiochip0", data_lines = "5,6,13,19,26,16,20,21",
                                                gain = "a128";
    unsigned clock_line = 17;
    double noise_n = 0.025;

    CLI::App* add(CLI::App& app) override {
        auto* sub = app.add_subcommand("run", "sample the cells and publish the wrench");
        sub->add_flag("--sim", sim, "emulated HX711 bank driven by the physics and the mocap topic (no hardware)");
        sub->add_option("--calibration", calibration_path,
                        "calibration YAML (default: nominal gains and the stand's geometry)");
        sub->add_option("--physics", physics_path,
                        "physics configuration for --sim (default: the documented defaults)");
        sub->add_option("--noise", noise_n, "--sim: load-cell noise, 1 sigma [N]")
            ->check(dw::cli::in(dw::physics::kCellNoiseRange));
        sub->add_option("--gpio-chip", gpio_chip, "GPIO chip (real hardware)");
        sub->add_option("--clock-line", clock_line, "PD_SCK line offset, shared by the 8 chips")
            ->check(dw::cli::in(dw::stand::kLineOffsetRange));
        sub->add_option("--data-lines", data_lines, "DOUT line offsets of cells 0-7, comma-separated");
        sub->add_option("--gain", gain, "the chips' channel and gain: a128 (default), a64 or b32");
        sub->add_flag("--realtime", realtime, "SCHED_FIFO and mlockall for the sampling thread");
        return sub;
    }
    int run() override {
        const auto physics = dw::physics::physics_or_defaults(physics_path);
        dw::stand::AgentOptions aopt;
        aopt.calibration = calibration_of(calibration_path, physics.stand);
        dw::stand::DriverOptions dopt;
        dopt.gain = dw::parse_entry(dw::stand::kGains, gain, "gain", "--gain");
        dw::dds::Participant participant(cli.dds(), "stand_agent", cli.clock());
        dw::dds::Heartbeat heartbeat(participant);
        // Simulated, the physics' clock effect is the agent's clock running late (the recording chain).
        dw::OffsetClock agent_clock(cli.clock(), sim ? dw::from_seconds(dw::stand::sim_clock_delay_s(physics)) : 0);
        dw::stand::StandAgent agent(aopt, agent_clock);
        std::unique_ptr<dw::stand::Hx711Lines> lines;
        std::unique_ptr<dw::stand::PhysicsSource> source;
        if (sim) {
            // The simulated world keeps the host's time, as the simulated motion capture stamps in.
            source = std::make_unique<dw::stand::PhysicsSource>(participant, physics, dw::SystemClock::instance());
            lines = emulated_lines(*source, physics, noise_n);
            dw::log::info("simulated stand: emulated HX711 bank driven by the physics and rt/", cli.dds().ns,
                          "/mocap/frame");
        } else {
            lines = gpio_lines();
        }
        dw::stand::Hx711Driver driver(*lines, dopt);
        heartbeat.set_state(dw::msg::PROC_RUNNING);
        dw::stand::RunOptions ro{realtime, dw::Shutdown::instance().token(), {}};
        if (source) ro.pipeline_delay_s = [&source] { return source->take_air_lag_s(); };
        const auto n = dw::stand::run_agent(participant, driver, agent, ro);
        dw::log::info("published ", n, " wrench samples", source ? source->summary() : "");
        return 0;
    }

private:
    std::unique_ptr<dw::stand::Hx711Lines> gpio_lines() const {
        dw::stand::GpioPins pins;
        pins.chip = gpio_chip;
        pins.clock = clock_line;
        const auto d = parse_lines(data_lines);
        std::copy(d.begin(), d.end(), pins.data.begin());
        return std::make_unique<dw::stand::GpiodLines>(pins);
    }
};

// `dw-stand-agent calibrate`: the cell-to-wrench matrix fitted to known loads.
struct CalibrateCommand final : dw::cli::Command {
    std::string loads_path, out_path = "stand-calibration.yaml", calibration_path;

    CLI::App* add(CLI::App& app) override {
        auto* sub = app.add_subcommand("calibrate", "fit the cell-to-wrench matrix by least squares from known loads");
        sub->add_option("--loads", loads_path, "CSV: c0..c7 (tared counts), f_n, f_e, f_d, m_roll, m_pitch, m_yaw")
            ->required();
        sub->add_option("--out", out_path, "calibration YAML to write");
        sub->add_option("--calibration", calibration_path, "take the per-cell gains from this file");
        return sub;
    }
    int run() override {
        const auto cal = calibration_of(calibration_path, dw::physics::PhysicsConfig{}.stand);
        dw::require_writable_path(out_path, "--out");
        const auto fit = dw::stand::fit_calibration(dw::stand::read_known_loads(loads_path), cal.counts_per_newton);
        fit.calibration.save(out_path);
        std::cout << "wrote " << out_path << ": residual " << fit.residual_rms << " (RMS over axes), condition number "
                  << fit.condition << "\n";
        return 0;
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-stand-agent: eight HX711 load cells to a calibrated 6-DOF wrench (80 Hz)");
    CLI::App& app = cli.app();
    app.require_subcommand(1);
    RunCommand run(cli);
    CalibrateCommand calibrate;
    return dw::cli::run_commands(app, {&run, &calibrate}, [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-stand-agent", [&] { return run(argc, argv); });
}
