#pragma once
// The hostile Motive's options (issue 70), for the emulator (`--new-ids-per-frame`, ...) and the
// bridge's simulated source (`--sim-new-ids-per-frame`, ...): one list, two prefixes.
#include <string>

#include "core/cli.hpp"
#include "core/log.hpp"
#include "mocap_bridge/emulator.hpp"

namespace dw::natnet {

inline void add_hostility_options(CLI::App& app, Hostility& h, const std::string& prefix) {
    const std::string what = prefix.empty() ? "hostile: " : "sim, hostile: ";
    app.add_option("--" + prefix + "new-ids-per-frame", h.new_ids_per_frame,
                   what + "this many more bodies every frame, each with an id never sent before")
        ->check(cli::in(kNewIdsPerFrameRange));
    app.add_flag("--" + prefix + "frozen-clock", h.frozen_clock, what + "every frame's timestamp the same");
    app.add_flag("--" + prefix + "hostile-packets", h.packets,
                 log::cat(what, "every ", kHostileEvery,
                          "th frame one more packet: cut short, oversized, or of NaN, inf and huge values"));
}

}  // namespace dw::natnet
