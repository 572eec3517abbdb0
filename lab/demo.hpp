#pragma once
// `dw-lab demo`: the whole lab in one command, simulated. Flies single-neighbour legs and a
// Leader Follower K=3 experiment with every process separate on loopback DDS (the lab file
// config/lab.sim.yaml), records MCAP, exports flight folders, trains and compares the models
// (naive linear, learnt linear, Deep Sets), draws maps, then explains a "real" flight made with
// a hidden effect — all into one run folder with an index.md.
#include <stop_token>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "dds/config.hpp"

namespace dw::lab {

struct DemoOptions {
    std::string out_dir;
    bool quick = false;                 // fewer legs and epochs (the CI test)
    int jobs = machine_cores();         // cores the study may use (dw-predictor study --jobs)
    std::vector<std::string> dds_args;  // for every process
    int viewer_port = 8765;             // dw-viewer's while the experiments fly (0: any free port)
    dds::DdsConfig dds;                 // the launcher's own participant
    std::stop_token stop;               // every step and child stops: dw::Stopped
};

// Returns the exit code (0 when every step succeeded).
int run_demo(const DemoOptions& o);

}  // namespace dw::lab
