// The viewer's pieces without a socket (issue 72): the Foxglove protocol's messages as its spec
// writes them, and a client's bounded outbox.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "viewer/foxglove.hpp"
#include "viewer/outbox.hpp"
#include "viewer/page.hpp"

using namespace dw::viewer;

TEST(Foxglove, TheOfferedSubprotocolIsEchoedAndTheServersMessagesAreTheSpecs) {
    EXPECT_EQ(choose_subprotocol("foxglove.sdk.v1")->subprotocol, "foxglove.sdk.v1");
    EXPECT_EQ(choose_subprotocol("chat, foxglove.websocket.v1")->subprotocol, "foxglove.websocket.v1");
    EXPECT_EQ(choose_subprotocol(" dw.json.v1 ")->dialect, Dialect::page);
    EXPECT_FALSE(choose_subprotocol("chat, superchat"));
    EXPECT_FALSE(choose_subprotocol(""));

    const auto info = nlohmann::json::parse(server_info("lab", "s1"));
    EXPECT_EQ(info["op"], "serverInfo");
    EXPECT_EQ(info["name"], "lab");
    EXPECT_TRUE(info["capabilities"].is_array());
    const std::vector<Channel> channels{{7, "rt/lab/stand/wrench", "dw::msg::WrenchStamped", "module dw {};"}};
    const auto ad = nlohmann::json::parse(advertise(channels));
    ASSERT_EQ(ad["channels"].size(), 1u);
    const auto& c = ad["channels"][0];
    EXPECT_EQ(c["id"], 7);
    EXPECT_EQ(c["topic"], "rt/lab/stand/wrench");
    EXPECT_EQ(c["encoding"], "cdr");
    EXPECT_EQ(c["schemaEncoding"], "omgidl");
    EXPECT_EQ(c["schemaName"], "dw::msg::WrenchStamped");
    EXPECT_EQ(c["schema"], "module dw {};");
    EXPECT_EQ(nlohmann::json::parse(status(StatusLevel::warning, "slow"))["level"], 1);

    const std::vector<std::uint8_t> payload{0, 1, 0, 0, 42};
    const auto m = message_data(0x01020304, 0x1122334455667788ull, payload);
    const std::vector<std::uint8_t> want{1,    0x04, 0x03, 0x02, 0x01, 0x88, 0x77, 0x66, 0x55,
                                         0x44, 0x33, 0x22, 0x11, 0,    1,    0,    0,    42};
    EXPECT_EQ(m, want);
}

TEST(Foxglove, AClientMaySubscribeAndUnsubscribeAndNothingElse) {
    const auto s =
        parse_client(R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":1,"channelId":4}]})");
    ASSERT_TRUE(std::holds_alternative<Subscribe>(s));
    EXPECT_EQ(std::get<Subscribe>(s).subscriptions,
              (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{0, 3}, {1, 4}}));
    const auto u = parse_client(R"({"op":"unsubscribe","subscriptionIds":[1]})");
    ASSERT_TRUE(std::holds_alternative<Unsubscribe>(u));
    EXPECT_EQ(std::get<Unsubscribe>(u).subscription_ids, std::vector<std::uint32_t>{1});
    // Read-only: publishing, parameters and services are refused, each in one line; so is nonsense.
    for (const char* text :
         {R"({"op":"advertise","channels":[]})", R"({"op":"setParameters","parameters":[]})", R"({"op":"callService"})",
          "not json", "[]", R"({"op":7})", R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":3}]})",
          R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":3}]})", R"({"op":"subscribe"})",
          R"({"op":"unsubscribe","subscriptionIds":["a"]})"}) {
        const auto r = parse_client(text);
        ASSERT_TRUE(std::holds_alternative<Refused>(r)) << text;
        EXPECT_FALSE(std::get<Refused>(r).why.empty()) << text;
        EXPECT_EQ(std::get<Refused>(r).why.find('\n'), std::string::npos) << text;
    }
}

TEST(Outbox, AStalledClientLosesItsOldestSensorFramesAndKeepsEachStatesNewest) {
    Outbox box;
    const std::size_t pushed = 3 * kMaxQueuedFrames;
    for (std::size_t i = 0; i < pushed; ++i) box.push_stream({true, std::to_string(i)});
    box.push_latest(5, "planner", {false, "state 1"});
    box.push_latest(5, "planner", {false, "state 2"});
    box.push_latest(5, "stand", {false, "stand"});
    EXPECT_EQ(box.dropped(), pushed - kMaxQueuedFrames);
    EXPECT_EQ(box.take_new_drops(), pushed - kMaxQueuedFrames);
    EXPECT_EQ(box.take_new_drops(), 0u);
    // The states first (each instance's newest only), then the newest kMaxQueuedFrames stream frames in order.
    EXPECT_EQ(box.pop()->bytes, "state 2");
    EXPECT_EQ(box.pop()->bytes, "stand");
    EXPECT_EQ(box.pop()->bytes, std::to_string(pushed - kMaxQueuedFrames));
    std::size_t left = 0;
    while (box.pop()) ++left;
    EXPECT_EQ(left, kMaxQueuedFrames - 1);
    EXPECT_EQ(box.bytes(), 0u);
    // Bytes bound it too: big frames leave fewer waiting.
    const std::string big(kMaxQueuedBytes / 4, 'x');
    for (int i = 0; i < 10; ++i) box.push_stream({true, big});
    EXPECT_LE(box.bytes(), kMaxQueuedBytes);
    EXPECT_EQ(box.dropped(), pushed - kMaxQueuedFrames + 6);
    // Instances named on the wire are held up to kMaxHeldStates; more wait as stream frames, which
    // are bounded: a writer inventing a name per sample does not grow the outbox.
    Outbox names;
    const std::size_t invented = kMaxHeldStates + 2 * kMaxQueuedFrames;
    for (std::size_t i = 0; i < invented; ++i) names.push_latest(1, "p" + std::to_string(i), {false, "s"});
    std::size_t frames = 0;
    while (names.pop()) ++frames;
    EXPECT_EQ(frames, kMaxHeldStates + kMaxQueuedFrames);
    EXPECT_EQ(names.dropped(), invented - frames);
}

TEST(ViewerPage, ThePagesFilesAreServedAndNothingElse) {
    ASSERT_NE(page_file("/"), nullptr);
    EXPECT_NE(page_file("/")->body.find("<canvas id=\"arena\""), std::string_view::npos);
    EXPECT_EQ(page_file("/index.html?x=1"), page_file("/"));
    ASSERT_NE(page_file("/app.js"), nullptr);
    EXPECT_NE(page_file("/app.js")->body.find("dw.json.v1"), std::string_view::npos);
    EXPECT_EQ(page_file("/app.js")->body.find("http"), std::string_view::npos) << "nothing fetched from elsewhere";
    EXPECT_EQ(page_file("/../etc/passwd"), nullptr);
    EXPECT_EQ(page_file("/nope"), nullptr);
}

// Hostile text never throws out of the viewer: a sample's string that is no UTF-8 (a malformed
// sample on the wire), a client's long operation name in many-byte letters cut at 40 bytes.
TEST(Foxglove, TextThatIsNoUtf8BecomesReplacementCharactersNotAnException) {
    const std::string bad =
        "run\xff\xfe"
        "id";
    std::string text;
    EXPECT_NO_THROW(text = json_text({{"run_id", bad}}));
    EXPECT_NE(text.find("\xef\xbf\xbd"), std::string::npos) << text;  // U+FFFD
    std::string op;
    for (int i = 0; i < 30; ++i) op += "\xc3\xa9";  // é × 30: 60 bytes
    const auto r = parse_client(R"({"op":")" + op + R"("})");
    ASSERT_TRUE(std::holds_alternative<Refused>(r));
    EXPECT_NO_THROW(text = status(StatusLevel::error, std::get<Refused>(r).why));
    EXPECT_FALSE(nlohmann::json::parse(text, nullptr, false).is_discarded()) << text;
}
