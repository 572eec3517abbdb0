#pragma once
// The viewer's side of the lab: a reader on every lab topic (dds/topics.hpp), each sample as its
// CDR payload (and, for the page, as JSON), handed to every attached client. State topics (the
// registry's state and heartbeat profiles: the plan, the experiment's state, the stand's and each
// process's status) keep their newest sample per instance, so a client that attaches late is given
// the truth at once. Reads only: the viewer publishes nothing on the lab.
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "dds/participant.hpp"
#include "viewer/foxglove.hpp"

namespace dw::viewer {

struct Sample {
    std::uint32_t channel = 0;
    std::string_view suffix;  // the topic after rt/<namespace>/, e.g. stand/wrench
    std::uint64_t log_time_ns = 0;
    std::span<const std::uint8_t> cdr;
    const std::string* json = nullptr;  // the message as JSON text; null when no client wants JSON
    std::string_view key;               // a keyed state topic's instance ("" otherwise)
    bool latest = false;                // a state topic: only its newest sample per instance matters
};

class Client {
public:
    virtual ~Client() = default;
    // On a DDS thread (or attach's): must not block.
    virtual void deliver(const Sample& s) = 0;
    virtual bool wants_json() const = 0;
};

class Hub {
public:
    explicit Hub(dds::Participant& participant);
    ~Hub();
    Hub(const Hub&) = delete;
    Hub& operator=(const Hub&) = delete;

    const std::vector<Channel>& channels() const { return channels_; }
    // Attaches c (held weakly: a client gone is dropped) and gives it every state topic's newest
    // samples first.
    void attach(const std::shared_ptr<Client>& c);
    // Stops delivering to c (before its server goes away).
    void detach(const Client* c);
    // Gives c channel's newest samples again (a state topic subscribed after c attached).
    void replay(Client& c, std::uint32_t channel);
    std::uint64_t received() const { return received_.load(); }

    class Reader;  // one lab topic's (hub.cpp)
    // From a Reader: a sample of channel `index` (message as bytes and, when asked, JSON).
    void publish(const Sample& s);
    bool json_wanted() const { return json_clients_.load() > 0; }

private:
    struct Held {
        std::uint32_t channel = 0;
        std::string suffix, key, json;
        std::uint64_t log_time_ns = 0;
        std::vector<std::uint8_t> cdr;
    };
    std::vector<std::shared_ptr<Client>> clients();
    void hold(const Sample& s);  // a state topic's newest sample per instance (up to kMaxHeldStates)

    std::vector<Channel> channels_;
    std::mutex mutex_;
    struct Attached {
        std::weak_ptr<Client> client;
        const Client* identity = nullptr;
        bool json = false;
    };
    std::vector<Attached> clients_;
    std::map<std::pair<std::uint32_t, std::string>, Held> latest_;
    std::atomic<int> json_clients_{0};
    std::atomic<std::uint64_t> received_{0};
    std::vector<std::unique_ptr<Reader>> readers_;  // last: their callbacks use the members above
};

}  // namespace dw::viewer
