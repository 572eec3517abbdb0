// Unit tests of configuration: YAML files with located errors, DDS config resolution/validation.
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "core/config.hpp"
#include "core/keys.hpp"
#include "dds/config.hpp"
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>

#include "support.hpp"

using dw::ConfigFile;
using dw::InputError;
using dw::dds::DdsCliOptions;
using dw::dds::DdsConfig;

namespace {
std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}
constexpr dw::Range kAnyInt{-1000, 1000};
}  // namespace

namespace {
// One section of a file read through core/keys.hpp, as each process's reader does.
struct Section {
    int domain = 0;
    std::string transport;
    std::vector<std::string> peers;
    int missing = -1;
};
Section read_dds(const ConfigFile& c) {
    Section s;
    dw::read_section(c.root(), c.path(), "dds", [&](dw::KeyVisitor& k) {
        k.integer("domain", s.domain, kAnyInt);
        k.text("transport", s.transport);
        k.texts("initial_peers", s.peers);
        k.integer("missing", s.missing, kAnyInt);
    });
    return s;
}
}  // namespace

TEST(ConfigFile, ASectionIsReadThroughItsKeys) {
    const auto c =
        ConfigFile::parse("dds:\n  domain: 7\n  transport: udp\n  initial_peers: [127.0.0.1, 10.0.0.2]\n", "t.yaml");
    const Section s = read_dds(c);
    EXPECT_EQ(s.domain, 7);
    EXPECT_EQ(s.transport, "udp");
    EXPECT_EQ(s.peers, (std::vector<std::string>{"127.0.0.1", "10.0.0.2"}));
    EXPECT_EQ(s.missing, -1) << "an absent key keeps its default";
    EXPECT_EQ(read_dds(ConfigFile::parse("other: {colour: red}\n", "o.yaml")).domain, 0)
        << "an absent section is all defaults, and other sections are other readers'";
}

TEST(ConfigFile, ReadingDoesNotInsertKeys) {
    const auto c = ConfigFile::parse("dds:\n  domain: 7\n", "t.yaml");
    (void)read_dds(c);
    EXPECT_EQ(c.root()["dds"].size(), 1u);
    EXPECT_EQ(c.root().size(), 1u);
}

TEST(ConfigFile, MalformedYamlNamesFileLineAndColumn) {
    const std::string e = error_of([] { ConfigFile::parse("dds:\n  domain: [1, 2\n", "bad.yaml"); });
    EXPECT_NE(e.find("bad.yaml:"), std::string::npos) << e;
    EXPECT_NE(e.find("not valid YAML"), std::string::npos) << e;
}

TEST(ConfigFile, WrongTypeNamesKeyAndLine) {
    const auto c = ConfigFile::parse("dds:\n  domain: seven\n", "t.yaml");
    EXPECT_EQ(error_of([&] { (void)read_dds(c); }), "t.yaml:2:11: dds.domain: expected an integer, got 'seven'");
    const auto list = ConfigFile::parse("dds:\n  initial_peers: 10.0.0.2\n", "t.yaml");
    EXPECT_EQ(error_of([&] { (void)read_dds(list); }), "t.yaml:2:18: dds.initial_peers: expected a list of words");
}

TEST(ConfigFile, UnreadableFileIsAnInputError) {
    const std::string e = error_of([] { ConfigFile::load("/nonexistent/lab.yaml"); });
    EXPECT_EQ(e, "config /nonexistent/lab.yaml: no such file");
}

TEST(ConfigFile, TopLevelMustBeAMapping) {
    EXPECT_NE(error_of([] { ConfigFile::parse("- a\n- b\n", "l.yaml"); }).find("l.yaml:1:1"), std::string::npos);
}

namespace {
// A configuration declared once (core/keys.hpp), read and written through the same list.
enum class Shade { light, dark };
constexpr std::array<const char*, 2> kShades = {"light", "dark"};
struct Toy {
    double gain = 1.5;
    int count = 3;
    bool on = false;
    Shade shade = Shade::light;
    std::array<double, 2> xy{0, 0};
    double lo = 0, hi = 1;
    std::vector<std::string> tags;
    std::map<std::string, std::string> labels;  // names the user chose
    std::vector<std::pair<std::string, double>> items;
};
void toy_collections(dw::KeyVisitor& k, Toy& t) {
    k.texts("tags", t.tags);
    k.section("labels", [&](dw::KeyVisitor& l) {
        std::vector<std::string> names;
        for (const auto& [n, v] : t.labels) names.push_back(n);
        l.names(names);
        for (const auto& n : names) l.text(n, t.labels[n]);
    });
    std::size_t count = t.items.size();
    k.list("items", count, [&](dw::KeyVisitor& item, std::size_t i) {
        if (t.items.size() <= i) t.items.resize(i + 1);
        item.require(item.has("name"), "name", "missing");
        item.text("name", t.items[i].first);
        item.number("weight", t.items[i].second, {0, 1});
    });
}
void toy_keys(dw::KeyVisitor& k, Toy& t) {
    k.constant("format", "toy/1");
    k.number("gain", t.gain, {0, 10});
    k.integer("count", t.count, {1, 9});
    k.flag("on", t.on);
    k.enumeration("shade", t.shade, kShades, "shade", "; nothing else");
    k.numbers("xy", t.xy, {-1, 1}, "expected [x, y]");
    k.section(
        "band",
        [&](dw::KeyVisitor& b) {
            b.number("lo", t.lo, {0, 5});
            b.number("hi", t.hi, {0, 5});
            b.require(t.hi > t.lo, "hi", "must be greater than lo");
        },
        "a band has lo and hi");
    toy_collections(k, t);
}
Toy read_toy(const std::string& yaml) {
    Toy t;
    dw::read_keys(dw::load_yaml(yaml, "t.yaml"), "t.yaml", [&](dw::KeyVisitor& k) { toy_keys(k, t); });
    return t;
}
std::string write_toy(Toy t) {
    YAML::Emitter o;
    dw::write_keys(o, [&](dw::KeyVisitor& k) { toy_keys(k, t); });
    return o.c_str();
}
}  // namespace

TEST(DeclaredKeys, WhatIsWrittenReadsBackTheSameAndAbsentKeysKeepTheirDefaults) {
    EXPECT_EQ(read_toy("").gain, 1.5);
    const Toy t = read_toy("gain: 2.5\ncount: 7\non: true\nshade: dark\nxy: [0.5, -0.25]\nband: {lo: 1, hi: 4}\n");
    EXPECT_EQ(t.gain, 2.5);
    EXPECT_EQ(t.count, 7);
    EXPECT_TRUE(t.on);
    EXPECT_EQ(t.shade, Shade::dark);
    EXPECT_EQ(t.xy[1], -0.25);
    EXPECT_EQ(t.hi, 4);
    const std::string text = write_toy(t);
    EXPECT_NE(text.find("format: toy/1"), std::string::npos) << text;
    EXPECT_NE(text.find("shade: dark"), std::string::npos) << text;
    EXPECT_EQ(write_toy(read_toy(text)), text);
}

TEST(DeclaredKeys, ListsNamedEntriesAndWordsReadAndWriteBack) {
    const Toy t =
        read_toy("tags: [a, b]\nlabels: {v1: red, v2: blue}\nitems:\n  - {name: x, weight: 0.5}\n  - {name: y}\n");
    EXPECT_EQ(t.tags, (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(t.labels, (std::map<std::string, std::string>{{"v1", "red"}, {"v2", "blue"}}));
    ASSERT_EQ(t.items.size(), 2u);
    EXPECT_EQ(t.items[0], std::make_pair(std::string("x"), 0.5));
    EXPECT_EQ(t.items[1].first, "y");
    const std::string text = write_toy(t);
    const Toy back = read_toy(text);
    EXPECT_EQ(back.labels, t.labels) << text;
    EXPECT_EQ(back.items, t.items) << text;
    EXPECT_EQ(write_toy(back), text);
}

// A rule is reported after every unknown key: the misspelt key is the cause, the rule its effect.
TEST(DeclaredKeys, ListItemsAreLocatedAndUnknownKeysComeBeforeBrokenRules) {
    const auto error = [](const std::string& yaml) { return error_of([&] { read_toy(yaml); }); };
    EXPECT_EQ(error("items:\n  - {name: x}\n  - {name: y, weight: 2}\n"),
              "t.yaml:3:23: items[1].weight: 2 is not in [0, 1]");
    EXPECT_EQ(error("items:\n  - {nmae: x}\n"), "t.yaml:2:6: items[0].nmae: unknown key 'nmae' (known: name, weight)");
    EXPECT_EQ(error("items:\n  - {weight: 1}\n"), "t.yaml:2:5: items[0].name: missing");
    EXPECT_EQ(error("band: {lo: 2, hi: 1}\ncolour: red\n"),
              "t.yaml:2:1: colour: unknown key 'colour' (known: band, count, format, gain, items, labels, on, shade, "
              "tags, xy)");
    EXPECT_EQ(error("items: 3\n"), "t.yaml:1:8: items: expected a list");
    EXPECT_EQ(error("tags: [a, [b]]\n"), "t.yaml:1:11: tags: expected a list of words");
}

// Issue 17: the same declarations as JSON (the predictor's model files): read by the same strict
// reader, written as JSON that an independent reader (nlohmann) takes back, numbers exact.
namespace {
struct Net {
    std::string name = "n";
    std::vector<double> bias;
    std::vector<double> weight;  // row-major
    std::size_t rows = 0, cols = 0;
    std::string notes = "{}";
};
void net_keys(dw::KeyVisitor& k, Net& n) {
    k.text("name", n.name);
    k.values("bias", n.bias, {-10, 10});
    k.matrix("weight", n.weight, n.rows, n.cols, {-10, 10});
    k.verbatim("notes", n.notes);
}
Net read_net(const std::string& json) {
    Net n;
    dw::read_keys(dw::load_yaml(json, "n.json", "JSON"), "n.json", [&](dw::KeyVisitor& k) { net_keys(k, n); });
    return n;
}
}  // namespace

TEST(DeclaredKeys, JsonIsReadStrictlyAndWrittenExactly) {
    Net n;
    n.name = "q\"uote\\d";
    n.bias = {0.1, -1e-7, 3};
    n.weight = {1.0 / 3, 2, 0.1f, -4, 5, 6};
    n.rows = 2;
    n.cols = 3;
    n.notes = R"({"trained_on":[{"name":"a b","k":3}],"ok":true,"none":null,"text":"0.5"})";
    const std::string text = dw::write_json_keys([&](dw::KeyVisitor& k) { net_keys(k, n); });
    const auto j = nlohmann::json::parse(text);  // an independent reader
    EXPECT_EQ(j["name"], n.name);
    EXPECT_EQ(j["weight"][0][0].get<double>(), 1.0 / 3);
    EXPECT_EQ(j["notes"]["trained_on"][0]["k"], 3);
    EXPECT_TRUE(j["notes"]["text"].is_string()) << "a quoted number stays a string";
    const Net back = read_net(text);
    EXPECT_EQ(back.name, n.name);
    EXPECT_EQ(back.bias, n.bias);
    EXPECT_EQ(back.weight, n.weight);
    EXPECT_EQ(back.rows, 2u);
    EXPECT_EQ(back.cols, 3u);
    EXPECT_EQ(nlohmann::json::parse(back.notes), nlohmann::json::parse(n.notes));
    EXPECT_EQ(dw::write_json_keys([&](dw::KeyVisitor& k) { net_keys(k, const_cast<Net&>(back)); }), text);

    const auto error = [](const std::string& json) { return error_of([&] { read_net(json); }); };
    EXPECT_EQ(error("{\"name\": \"x\",\n \"bais\": []}"),
              "n.json:2:2: bais: unknown key 'bais' (known: bias, name, notes, weight)");
    EXPECT_EQ(error(R"({"weight": [[1, 2], [3]]})"), "n.json:1:21: weight[1]: rows differ in length");
    EXPECT_EQ(error(R"({"weight": [[1, "x"]]})"), "n.json:1:17: weight[0][1]: expected a number");
    EXPECT_EQ(error(R"({"bias": [1, 20]})"), "n.json:1:14: bias[1]: 20 is not in [-10, 10]");
    EXPECT_TRUE(error("{").starts_with("n.json:1:")) << error("{");
    EXPECT_NE(error("{").find(": not valid JSON: "), std::string::npos) << error("{");
    EXPECT_THROW(dw::write_json_keys([&](dw::KeyVisitor& k) {
                     double nan = std::nan("");
                     k.number("x", nan, {-1, 1});
                 }),
                 dw::RuntimeError)
        << "JSON has no NaN";
}

TEST(DeclaredKeys, EachMistakeIsOneLocatedLine) {
    const auto error = [](const std::string& yaml) { return error_of([&] { read_toy(yaml); }); };
    EXPECT_EQ(error("format: toy/2\n"), "t.yaml:1:9: format: expected toy/1");
    EXPECT_EQ(error("format: \"\"\n"), "t.yaml:1:9: format: expected toy/1");
    EXPECT_EQ(error("shade: \"\"\n"), "t.yaml:1:8: shade: unknown shade '' (expected light or dark; nothing else)");
    EXPECT_EQ(error("gain: 11\n"), "t.yaml:1:7: gain: 11 is not in [0, 10]");
    EXPECT_EQ(error("count: 2.5\n"), "t.yaml:1:8: count: expected a whole number");
    EXPECT_EQ(error("on: maybe\n"), "t.yaml:1:5: on: expected true or false");
    EXPECT_EQ(error("shade: pink\n"), "t.yaml:1:8: shade: unknown shade 'pink' (expected light or dark; nothing else)");
    EXPECT_EQ(error("xy: [1]\n"), "t.yaml:1:5: xy: expected [x, y]");
    EXPECT_EQ(error("band:\n  lo: 2\n  hi: 1\n"), "t.yaml:3:7: band.hi: must be greater than lo");
    EXPECT_EQ(error("band:\n  mid: 2\n"),
              "t.yaml:2:3: band.mid: unknown key 'mid': a band has lo and hi (expected hi or lo)");
    EXPECT_EQ(
        error("gian: 2\n"),
        "t.yaml:1:1: gian: unknown key 'gian' (known: band, count, format, gain, items, labels, on, shade, tags, xy)");
    EXPECT_EQ(error("band: 3\n"), "t.yaml:1:7: band: expected a mapping of keys");
}

TEST(DdsConfig, DefaultsAreLocalDomainZeroNamespaceLab) {
    const DdsConfig c = dw::dds::resolve({}, ConfigFile());
    EXPECT_EQ(c.domain, 0);
    EXPECT_EQ(c.profile, dw::dds::Profile::local);
    EXPECT_EQ(c.transport, dw::dds::Transport::default_);
    EXPECT_EQ(c.ns, "lab");
}

TEST(DdsConfig, CliOverridesFileOverridesDefaults) {
    const auto file = ConfigFile::parse("dds:\n  domain: 7\n  transport: udp\n  namespace: bench\n", "f.yaml");
    DdsCliOptions cli;
    cli.domain = 9;
    const DdsConfig c = dw::dds::resolve(cli, file);
    EXPECT_EQ(c.domain, 9);
    EXPECT_EQ(c.transport, dw::dds::Transport::udp);
    EXPECT_EQ(c.ns, "bench");
}

TEST(DdsConfig, UnknownTransportIsOneClearLine) {
    DdsCliOptions cli;
    cli.transport = "carrier-pigeon";
    EXPECT_EQ(error_of([&] { dw::dds::resolve(cli, ConfigFile()); }),
              "unknown transport 'carrier-pigeon' (expected default, shm or udp)");
}

TEST(DdsConfig, UnknownTransportInFileNamesFileLineAndKey) {
    const auto file = ConfigFile::parse("dds:\n  transport: tcp\n", "lab.yaml");
    EXPECT_EQ(error_of([&] { dw::dds::resolve({}, file); }),
              "lab.yaml:2:14: dds.transport: unknown transport 'tcp' (expected default, shm or udp)");
}

TEST(DdsConfig, DomainOutOfRange) {
    for (int bad : {-1, 233, 1000}) {
        DdsCliOptions cli;
        cli.domain = bad;
        EXPECT_NE(error_of([&] { dw::dds::resolve(cli, ConfigFile()); }).find("out of range (0-232)"),
                  std::string::npos);
    }
    const auto file = ConfigFile::parse("dds:\n  domain: 500\n", "lab.yaml");
    EXPECT_EQ(error_of([&] { dw::dds::resolve({}, file); }), "lab.yaml:2:11: dds.domain: 500 is not in [0, 232]");
    DdsCliOptions ok;
    ok.domain = 232;
    EXPECT_EQ(dw::dds::resolve(ok, ConfigFile()).domain, 232);
}

// A misspelt key was silently ignored; now it is one line naming it and the known ones (since issue
// 43 the closest three when all of them would make the line long).
TEST(DdsConfig, AnUnknownKeyInTheFileIsRefusedWhereItIs) {
    const auto file = ConfigFile::parse("dds:\n  domain: 3\n  domian: 4\n", "lab.yaml");
    const std::string e = error_of([&] { dw::dds::resolve({}, file); });
    EXPECT_EQ(e.rfind("lab.yaml:3:3: dds.domian: unknown key 'domian' (known: domain, ", 0), 0u) << e;
    EXPECT_NE(e.find("; the closest of 11)"), std::string::npos) << e;
    EXPECT_EQ(dw::dds::resolve({}, ConfigFile::parse("other:\n  colour: red\n", "lab.yaml")).domain, 0)
        << "other sections are other readers'";
}

TEST(DdsConfig, AddressesAreChecked) {
    DdsCliOptions cli;
    cli.peers = {"not-an-ip"};
    EXPECT_NE(error_of([&] { dw::dds::resolve(cli, ConfigFile()); }).find("not an IPv4 address"), std::string::npos);
    DdsCliOptions ds;
    ds.profile = "lab";
    ds.insecure = true;
    ds.discovery_server = "127.0.0.1";
    EXPECT_NE(error_of([&] { dw::dds::resolve(ds, ConfigFile()); }).find("needs a port"), std::string::npos);
    ds.discovery_server = "127.0.0.1:11811";
    EXPECT_EQ(dw::dds::resolve(ds, ConfigFile()).discovery_server, "127.0.0.1:11811");
}

TEST(DdsConfig, DiscoveryServerNeedsLabProfile) {
    DdsCliOptions cli;
    cli.discovery_server = "127.0.0.1:11811";
    EXPECT_NE(error_of([&] { dw::dds::resolve(cli, ConfigFile()); }).find("needs the lab profile"), std::string::npos);
}

TEST(DdsConfig, LocalProfileKeepsUdpOnLoopback) {
    DdsConfig c;
    const auto qos = dw::dds::participant_qos(c, "t");
    EXPECT_FALSE(qos.transport().use_builtin_transports);
    bool saw_udp = false;
    for (const auto& t : qos.transport().user_transports) {
        if (auto udp = std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(t)) {
            saw_udp = true;
            ASSERT_EQ(udp->interfaceWhiteList.size(), 1u);
            EXPECT_EQ(udp->interfaceWhiteList[0], "127.0.0.1");
        }
    }
    EXPECT_TRUE(saw_udp);
    ASSERT_EQ(qos.wire_protocol().builtin.initialPeersList.size(), 1u);
}

// The default is UDP alone: shared memory is used only when asked (dds/config.cpp says why).
TEST(DdsConfig, TheDefaultTransportIsUdpAlone) {
    for (const auto profile : {dw::dds::Profile::local, dw::dds::Profile::lab}) {
        DdsConfig c;
        c.profile = profile;
        const auto qos = dw::dds::participant_qos(c, "t");
        ASSERT_EQ(qos.transport().user_transports.size(), 1u);
        EXPECT_TRUE(std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(
            qos.transport().user_transports[0]));
    }
}

TEST(DdsConfig, ShmTransportHasNoUdp) {
    DdsConfig c;
    c.transport = dw::dds::Transport::shm;
    const auto qos = dw::dds::participant_qos(c, "t");
    ASSERT_EQ(qos.transport().user_transports.size(), 1u);
    EXPECT_TRUE(std::dynamic_pointer_cast<eprosima::fastdds::rtps::SharedMemTransportDescriptor>(
        qos.transport().user_transports[0]));
}

TEST(DdsConfig, DiscoveryServerMakesAClient) {
    DdsConfig c;
    c.profile = dw::dds::Profile::lab;
    c.insecure = true;  // the lab profile without a keystore
    c.discovery_server = "127.0.0.1:11811";
    const auto qos = dw::dds::participant_qos(c, "t");
    const auto& d = qos.wire_protocol().builtin.discovery_config;
    EXPECT_EQ(d.discoveryProtocol, eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT);
    ASSERT_EQ(d.m_DiscoveryServers.size(), 1u);
    EXPECT_EQ(d.m_DiscoveryServers.front().metatrafficUnicastLocatorList.begin()->port, 11811u);
}

TEST(DdsConfig, TheLabProfileWantsAKeystoreFromTheFileOrTheFlags) {
    const auto file = ConfigFile::parse("dds:\n  profile: lab\n", "lab.yaml");
    EXPECT_NE(error_of([&] { dw::dds::resolve({}, file); }).find("--insecure"), std::string::npos);
    DdsCliOptions keys;
    keys.security = "keys";
    EXPECT_EQ(dw::dds::resolve(keys, file).security, "keys");  // the file's profile, the flag's keystore
    DdsCliOptions open;
    open.insecure = true;
    EXPECT_TRUE(dw::dds::resolve(open, file).insecure);
    EXPECT_EQ(dw::dds::resolve({}, ConfigFile::parse("dds:\n  profile: lab\n  security: keys\n", "lab.yaml")).security,
              "keys");
}
