#include "viewer/outbox.hpp"

namespace dw::viewer {

void Outbox::push_stream(Frame f) {
    std::lock_guard lock(mutex_);
    bytes_ += f.bytes.size();
    stream_.push_back(std::move(f));
    while (stream_.size() > 1 && (stream_.size() > kMaxQueuedFrames || bytes_ > kMaxQueuedBytes)) {
        bytes_ -= stream_.front().bytes.size();
        stream_.pop_front();
        ++dropped_, ++new_drops_;
    }
}

void Outbox::push_latest(std::uint32_t channel, const std::string& key, Frame f) {
    std::unique_lock lock(mutex_);
    if (latest_.size() >= kMaxHeldStates && !latest_.contains({channel, key})) {
        lock.unlock();
        return push_stream(std::move(f));
    }
    auto& slot = latest_[{channel, key}];
    bytes_ += f.bytes.size();
    bytes_ -= slot.bytes.size();
    slot = std::move(f);
}

std::optional<Frame> Outbox::pop() {
    std::lock_guard lock(mutex_);
    if (!latest_.empty()) {
        auto node = latest_.extract(latest_.begin());
        bytes_ -= node.mapped().bytes.size();
        return std::move(node.mapped());
    }
    if (stream_.empty()) return std::nullopt;
    Frame f = std::move(stream_.front());
    stream_.pop_front();
    bytes_ -= f.bytes.size();
    return f;
}

std::uint64_t Outbox::dropped() const {
    std::lock_guard lock(mutex_);
    return dropped_;
}

std::uint64_t Outbox::take_new_drops() {
    std::lock_guard lock(mutex_);
    return std::exchange(new_drops_, 0);
}

std::size_t Outbox::bytes() const {
    std::lock_guard lock(mutex_);
    return bytes_;
}

}  // namespace dw::viewer
