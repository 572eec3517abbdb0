#pragma once
// Error kinds every lab process maps to exit codes: bad input (usage, config, data) exits 2,
// a runtime failure exits 1. The message is one line saying what and where.
#include <stdexcept>
#include <string>

namespace dw {

inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntime = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitStopped = 130;  // stopped on request (Ctrl-C, SIGTERM), as shells report SIGINT

// Bad usage, configuration or input data: the user can fix it. Exit code 2.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Something failed at run time (DDS entity creation, I/O, a peer lost). Exit code 1.
class RuntimeError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Long work gave up because a stop was requested. Exit code 130; nothing half-written is left.
class Stopped : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace dw
