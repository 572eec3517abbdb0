#include "viewer/hub.hpp"

#include <algorithm>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/cdr.hpp"
#include "dds/endpoint.hpp"
#include "dds/msg_json.hpp"
#include "dds/topics.hpp"
#include "idl/idl_texts.hpp"
#include "viewer/outbox.hpp"

namespace dw::viewer {

namespace {
// A keyed topic's instance: its @key field (a vehicle's or a process's name).
template <class T>
std::string key_of(const T& m) {
    if constexpr (requires { m.process(); }) return m.process();
    else if constexpr (requires { m.vehicle_id(); }) return m.vehicle_id();
    else return {};
}

// The profiles whose topics hold state: their newest sample is what a client must see.
bool holds_state(dds::QosProfile q) { return q == dds::QosProfile::state || q == dds::QosProfile::heartbeat; }
}  // namespace

class Hub::Reader {
public:
    virtual ~Reader() = default;
};

namespace {
template <class T>
class TypedReader final : public Hub::Reader {
public:
    TypedReader(dds::Participant& p, const dds::Topic<T>& spec, std::uint32_t channel, Hub& hub)
        : hub_(hub),
          channel_(channel),
          suffix_(spec.suffix),
          latest_(holds_state(spec.qos)),
          reader_(p, spec, [this](const T& m, const dds::SampleMeta& meta) { on_sample(m, meta); }) {}

private:
    void on_sample(const T& m, const dds::SampleMeta& meta) {
        std::lock_guard lock(mutex_);  // the buffers below
        const auto cdr = cdr_.serialize(m);
        if (cdr.empty()) return;
        const bool json = latest_ || hub_.json_wanted();
        if (json) json_ = json_text(dds::to_json(m));
        const std::string key = key_of(m);
        hub_.publish({channel_, suffix_, static_cast<std::uint64_t>(meta.reception_time_ns), cdr,
                      json ? &json_ : nullptr, key, latest_});
    }

    Hub& hub_;
    std::uint32_t channel_;
    std::string_view suffix_;
    bool latest_;
    std::mutex mutex_;
    dds::CdrWriter<T> cdr_;
    std::string json_;
    dds::Reader<T> reader_;  // last: its callback uses the members above
};
}  // namespace

Hub::Hub(dds::Participant& participant) {
    dds::topics::for_each([&](const auto& spec) {
        using T = typename std::decay_t<decltype(spec)>::type;
        const auto id = static_cast<std::uint32_t>(channels_.size() + 1);
        try {
            readers_.push_back(std::make_unique<TypedReader<T>>(participant, spec, id, *this));
        } catch (const RuntimeError& e) {  // a secure lab whose permissions do not let it read this topic
            log::warn("not showing ", participant.topic_name(spec.suffix), ": ", e.what());
            return;
        }
        channels_.push_back(
            {id, participant.topic_name(spec.suffix), std::string(spec.type_name), idl::resolved(spec.idl)});
    });
}

Hub::~Hub() {
    readers_.clear();  // no callback after this
}

std::vector<std::shared_ptr<Client>> Hub::clients() {
    std::lock_guard lock(mutex_);
    std::vector<std::shared_ptr<Client>> out;
    std::erase_if(clients_, [&](const Attached& a) {
        if (auto c = a.client.lock()) {
            out.push_back(std::move(c));
            return false;
        }
        if (a.json) --json_clients_;
        return true;
    });
    return out;
}

void Hub::attach(const std::shared_ptr<Client>& c) {
    std::vector<Held> held;
    {
        std::lock_guard lock(mutex_);
        clients_.push_back({c, c.get(), c->wants_json()});
        if (c->wants_json()) ++json_clients_;
        for (const auto& [k, h] : latest_) held.push_back(h);
    }
    for (const auto& h : held) c->deliver({h.channel, h.suffix, h.log_time_ns, h.cdr, &h.json, h.key, true});
}

void Hub::detach(const Client* c) {
    std::lock_guard lock(mutex_);
    std::erase_if(clients_, [&](const Attached& a) {
        const bool gone = a.identity == c || a.client.expired();
        if (gone && a.json) --json_clients_;
        return gone;
    });
}

void Hub::replay(Client& c, std::uint32_t channel) {
    std::vector<Held> held;
    {
        std::lock_guard lock(mutex_);
        for (const auto& [k, h] : latest_)
            if (k.first == channel) held.push_back(h);
    }
    for (const auto& h : held) c.deliver({h.channel, h.suffix, h.log_time_ns, h.cdr, &h.json, h.key, true});
}

void Hub::publish(const Sample& s) {
    ++received_;
    if (s.latest) hold(s);
    for (const auto& c : clients()) c->deliver(s);
}

void Hub::hold(const Sample& s) {
    std::lock_guard lock(mutex_);
    const std::pair<std::uint32_t, std::string> at{s.channel, std::string(s.key)};
    if (latest_.size() >= kMaxHeldStates && !latest_.contains(at)) return;  // names from the wire: bounded
    latest_[at] = {s.channel,          std::string(s.suffix),
                   std::string(s.key), s.json ? *s.json : std::string(),
                   s.log_time_ns,      std::vector<std::uint8_t>(s.cdr.begin(), s.cdr.end())};
}

}  // namespace dw::viewer
