#pragma once
// What the explainer's simulated studies (`dw-explain proof`, `unnamed`) share: progress reported
// from several flights at once, one line at a time, and the cases asked for checked first.
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/names.hpp"

namespace dw::analysis {

// A progress callback that many threads may call: one line at a time, in order of arrival.
class StudyProgress {
public:
    explicit StudyProgress(std::function<void(const std::string&)> out) : out_(std::move(out)) {}
    void operator()(const std::string& line) {
        std::lock_guard lock(m_);
        if (out_) out_(line);
    }

private:
    std::mutex m_;
    std::function<void(const std::string&)> out_;
};

// Throws dw::InputError naming the first case of `asked` that is not in `known` (and the known ones).
inline void require_known_cases(const std::vector<std::string>& asked, const std::vector<std::string>& known) {
    for (const auto& n : asked)
        if (!find_name(known, n)) throw InputError("--cases: " + unknown_name_problem("case", n, known));
}

}  // namespace dw::analysis
