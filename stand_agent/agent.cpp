#include "stand_agent/agent.hpp"

#include <algorithm>
#include <cmath>

#include "core/log.hpp"
#include "dds/time.hpp"
#include "physics/stand.hpp"

namespace dw::stand {

StandAgent::StandAgent(const AgentOptions& options, Clock& clock) : options_(options), clock_(clock) {}

void StandAgent::set_state(msg::StandState s, std::string message, std::vector<std::uint32_t> faults) {
    state_ = s;
    message_ = std::move(message);
    fault_cells_ = std::move(faults);
}

void StandAgent::request_tare() {
    taring_left_ = options_.tare_samples;
    tare_sum_.setZero();
    set_state(msg::STAND_TARING, log::cat("taring at hover thrust: averaging ", options_.tare_samples, " samples"));
}

std::int32_t StandAgent::filter(int cell, std::int32_t raw, msg::CellStatus& status) {
    auto& h = history_[static_cast<std::size_t>(cell)];
    auto median_of = [](std::deque<std::int32_t> v) {
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    const bool saturated = raw == physics::kCountsMax || raw == physics::kCountsMin;
    if (h.size() >= 3) {
        const std::int32_t med = median_of(h);
        std::deque<std::int32_t> dev;
        for (auto x : h) dev.push_back(std::abs(x - med));
        const double mad = 1.4826 * median_of(dev);
        const double floor =
            options_.spike_min_n * options_.calibration.counts_per_newton[static_cast<std::size_t>(cell)];
        const double limit = std::max(options_.hampel_k * mad, std::abs(floor));
        if (saturated || std::abs(static_cast<double>(raw) - med) > limit) {
            status = saturated ? msg::CELL_SATURATED : msg::CELL_SPIKE;
            ++spikes_;
            return med;  // the spike never reaches the wrench
        }
    } else if (saturated) {
        status = msg::CELL_SATURATED;
        ++spikes_;
        return h.empty() ? 0 : h.back();
    }
    h.push_back(raw);
    if (static_cast<int>(h.size()) > options_.hampel_window) h.pop_front();
    status = msg::CELL_OK;
    return raw;
}

StandAgent::Output StandAgent::process(const Hx711Sample& s) {
    Output out;
    const msg::StandState before = state_;
    const std::string before_msg = message_;
    if (s.not_ready != 0 || s.stuck != 0) {
        const std::uint8_t bad = s.not_ready | s.stuck;
        std::vector<std::uint32_t> cells;
        for (std::uint32_t c = 0; c < kChips; ++c) {
            if (bad & (1u << c)) cells.push_back(c);
        }
        ++discarded_;
        set_state(msg::STAND_FAULT,
                  log::cat("cell", cells.size() > 1 ? "s " : " ", log::join(cells),
                           s.not_ready ? " not ready within the timeout: unplugged, unpowered or broken?"
                                       : " DOUT stuck low: shorted line or dead chip?"),
                  cells);
        out.status_changed = state_ != before || message_ != before_msg;
        return out;
    }
    if (s.timing_violation) {
        ++discarded_;  // chips may have powered down mid-word: nothing of this sample is trusted
        return out;
    }
    if (state_ == msg::STAND_FAULT || state_ == msg::STAND_STARTING) {
        set_state(msg::STAND_RUNNING, tared_ ? "all cells ready" : "all cells ready; not tared yet (send CALIBRATE)");
    }

    CellVector counts;
    for (int c = 0; c < kChips; ++c) {
        msg::CellStatus st = msg::CELL_OK;
        counts[c] = filter(c, s.counts[static_cast<std::size_t>(c)], st);
        out.frame.counts()[static_cast<std::size_t>(c)] = s.counts[static_cast<std::size_t>(c)];
        out.frame.status()[static_cast<std::size_t>(c)] = st;
    }
    if (taring_left_ > 0) {
        tare_sum_ += counts;
        if (--taring_left_ == 0) {
            zero_ = tare_sum_ / options_.tare_samples;
            tared_ = true;
            last_tare_ns_ = clock_.now_ns();
            set_state(msg::STAND_RUNNING, "tared at hover thrust");
        }
    }
    // Stamped when the conversions were read (the read began microseconds before this).
    const Nanos stamp = clock_.now_ns() - (clock_.monotonic_ns() - s.started_ns);
    out.frame.header().stamp(dds::to_msg(stamp));
    out.frame.gain(128);
    const physics::Wrench w = options_.calibration.wrench(counts - zero_);
    out.wrench.header().stamp(dds::to_msg(stamp));
    out.wrench.force_n().x(w[0]);
    out.wrench.force_n().y(w[1]);
    out.wrench.force_n().z(w[2]);
    out.wrench.torque_nm().x(w[3]);
    out.wrench.torque_nm().y(w[4]);
    out.wrench.torque_nm().z(w[5]);
    out.wrench.tared(tared_);
    out.publish = true;
    ++published_;
    const Nanos now = clock_.monotonic_ns();
    recent_.push_back(now);
    while (!recent_.empty() && now - recent_.front() > kNanosPerSecond) recent_.pop_front();
    out.status_changed = state_ != before || message_ != before_msg;
    return out;
}

msg::StandStatus StandAgent::status() const {
    msg::StandStatus s;
    s.header().stamp(dds::to_msg(clock_.now_ns()));
    s.state(state_);
    s.fault_cells(fault_cells_);
    s.message(message_);
    s.sample_rate_hz(static_cast<double>(recent_.size()));
    s.samples_published(published_);
    s.samples_discarded(discarded_);
    s.spikes_rejected(spikes_);
    for (int c = 0; c < kChips; ++c) s.tare_offset_counts()[static_cast<std::size_t>(c)] = zero_[c];
    s.last_tare(dds::to_msg(last_tare_ns_));
    s.pipeline_delay_s(-1);  // not measured: the runner sets it where a simulated stand measures it
    return s;
}

}  // namespace dw::stand
