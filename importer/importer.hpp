#pragma once
// Importers turn another lab's recordings into a flight folder (downwash-flight/1). One importer
// per source format, all behind this interface, so the next lab's format is one more file.
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>
#include <string_view>
#include <vector>

#include "core/numbers.hpp"
#include "flight/flight.hpp"

namespace dw::importer {

// A thrust estimated from PWM lags the command: T_lag[i+1] = a T_lag[i] + (1 − a) T[i] per sample
// (the Neural-Swarm authors' a = 0.84 at 100 Hz). Another a is for checking that choice on a lab's
// own flights (docs/REAL.md measures it on vehicles flying alone).
inline constexpr double kAuthorsThrustLag = 0.84;
inline constexpr Range kThrustLagRange{0, 0.99};

// An import holds one trial in memory (its logs, then the flight made from them: about 450 bytes a
// sample), so a trial is capped (issue 70: a 10-million-row log peaked at 3.9 GB): at most this
// many samples over all its logs (2.8 hours of one vehicle at 100 Hz; the shared collection's
// logs hold 1 700-6 500 each), and a binary log at most this many bytes (some 600 000 samples
// in the shared logs' layout, about 100 bytes each). A CSV log is read line by line, never whole.
// docs/HOSTILE_INPUT.md gives the peak memory measured at the cap.
inline constexpr std::size_t kMaxTrialSamples = 1'000'000;
inline constexpr std::uintmax_t kMaxBinaryLogBytes = 64ull << 20;

struct ImportOptions {
    std::string sufferer;                          // "" = the importer's default choice
    std::function<void(const std::string&)> warn;  // gaps, ground touches, steep tilts, damage
    std::stop_token stop;
    double thrust_lag = kAuthorsThrustLag;  // a, above: 0 = no lag
};

class Importer {
public:
    virtual ~Importer() = default;
    virtual std::string_view name() const = 0;  // the command word: dw-import <name> ...
    virtual std::string_view description() const = 0;
    // Throws dw::InputError naming the file and what is wrong.
    virtual flight::Flight import(const std::vector<std::string>& logs, const ImportOptions& o) const = 0;
};

// Every importer, in one list.
const std::vector<const Importer*>& importers();

}  // namespace dw::importer
