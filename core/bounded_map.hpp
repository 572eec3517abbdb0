#pragma once
// A map that holds at most `capacity` keys: making room for one more forgets the one used least
// recently. For state kept per key where the keys arrive from the network (rigid-body ids, body
// names, process names): a sender that invents a new key every frame then costs a bounded amount
// of memory, and the keys in use — touched every frame — are never the ones forgotten.
#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>

namespace dw {

template <class K, class V>
class BoundedMap {
public:
    explicit BoundedMap(std::size_t capacity) : capacity_(capacity < 1 ? 1 : capacity) {}

    // The value at k, made (default) if absent; marks k as just used.
    V& operator[](const K& k) {
        auto it = entries_.find(k);
        if (it == entries_.end()) {
            if (entries_.size() >= capacity_) forget_least_recent();
            it = entries_.emplace(k, Entry{}).first;
        }
        it->second.used = ++clock_;
        return it->second.value;
    }
    // The value at k without marking it used; nullptr if absent.
    const V* find(const K& k) const {
        const auto it = entries_.find(k);
        return it == entries_.end() ? nullptr : &it->second.value;
    }
    void clear() { entries_.clear(); }
    std::size_t size() const { return entries_.size(); }
    std::size_t capacity() const { return capacity_; }
    std::uint64_t forgotten() const { return forgotten_; }  // keys forgotten to make room, ever
    template <class F>
    void for_each(F&& f) const {  // f(key, value), in key order
        for (const auto& [k, e] : entries_) f(k, e.value);
    }
    template <class F>
    void for_each(F&& f) {  // f(key, value&), in key order; does not mark them used
        for (auto& [k, e] : entries_) f(k, e.value);
    }

private:
    struct Entry {
        V value{};
        std::uint64_t used = 0;
    };
    // A linear scan: it runs only when a new key arrives at capacity, and the capacities are small.
    void forget_least_recent() {
        auto oldest = entries_.begin();
        for (auto it = entries_.begin(); it != entries_.end(); ++it)
            if (it->second.used < oldest->second.used) oldest = it;
        entries_.erase(oldest);
        ++forgotten_;
    }
    std::size_t capacity_;
    std::map<K, Entry> entries_;
    std::uint64_t clock_ = 0;
    std::uint64_t forgotten_ = 0;
};

}  // namespace dw
