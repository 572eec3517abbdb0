#pragma once
// The shared Neural-Swarm collection (../shared/data/neural-swarm/, no licence: read in place,
// never copied into the repository). Tests that need it skip with the reason when it is absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace dw::test {

inline const std::string kNeuralSwarm =
    std::string(DW_SOURCE_DIR) + "/../shared/data/neural-swarm/data/training/datacollection21_06_16_2020/";

#define REQUIRE_SHARED_DATA()                             \
    if (!std::filesystem::exists(dw::test::kNeuralSwarm)) \
    GTEST_SKIP() << "the shared Neural-Swarm logs are not at " << dw::test::kNeuralSwarm

// One trial: its logs (the sufferer first) and a name.
struct Trial {
    std::string name;
    std::vector<std::string> logs;  // relative to kNeuralSwarm
    std::string sufferer;           // "" = the importer's default (the lowest)
    std::vector<std::string> paths() const {
        std::vector<std::string> out;
        for (const auto& l : logs) out.push_back(kNeuralSwarm + l);
        return out;
    }
};

// Every shared trial; the random walk twice, each vehicle the sufferer once.
inline const std::vector<Trial>& shared_trials() {
    static const std::vector<Trial> trials = {
        {"swap_ss", {"swap_ss/cf50_01.csv", "swap_ss/cf51_01.csv"}, ""},
        {"swap_sl_small_under_large", {"swap_sl/cf51_01.csv", "swap_sl/cf101_01.csv"}, ""},
        {"swap_sl_large_under_small", {"swap_sl/cf101_02.csv", "swap_sl/cf51_02.csv"}, ""},
        {"swap_ssl", {"swap_ssl/cf51_05.csv", "swap_ssl/cf101_05.csv", "swap_ssl/cf50_05.csv"}, ""},
        {"randomwalk_cf50", {"randomwalk_ss/cf50_02", "randomwalk_ss/cf51_02"}, "cf50"},
        {"randomwalk_cf51", {"randomwalk_ss/cf50_02", "randomwalk_ss/cf51_02"}, "cf51"},
    };
    return trials;
}

// The physics configuration for these vehicles (config/physics.crazyflie.yaml).
inline std::string crazyflie_physics() { return std::string(DW_SOURCE_DIR) + "/config/physics.crazyflie.yaml"; }
// The hand-made base it was calibrated from (config/physics.crazyflie-uncalibrated.yaml).
inline std::string crazyflie_uncalibrated_physics() {
    return std::string(DW_SOURCE_DIR) + "/config/physics.crazyflie-uncalibrated.yaml";
}

}  // namespace dw::test
