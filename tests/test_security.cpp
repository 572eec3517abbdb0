// Issue 18: the lab's DDS Security keystore (dw-lab keys) and participants that use it, in one
// process on loopback: who may publish and read what is what the topic registry says.
#include <arpa/inet.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <net/if.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <filesystem>
#include <regex>
#include <fstream>
#include <mutex>
#include <thread>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "dds/config.hpp"
#include "dds/endpoint.hpp"
#include "dds/heartbeat.hpp"
#include "dds/openssl.hpp"
#include "dds/qos.hpp"
#include "dds/security.hpp"
#include "probe/samples.hpp"
#include "security/keystore.hpp"
#include "security/policy.hpp"
#include "support.hpp"
#include "viewer/hub.hpp"

using namespace std::chrono_literals;
using dw::dds::Participant;
namespace topics = dw::dds::topics;

namespace {

std::string make_keystore(const dw::test::TempDir& dir) {
    dw::security::KeystoreOptions o;
    o.dir = dir.file("keys");
    o.days = 30;
    o.identities = dw::security::role_identities();
    dw::security::create_keystore(o);
    return o.dir;
}

// One keystore for the suite: making keys is the slow part.
const std::string& keystore() {
    static dw::test::TempDir dir;
    static const std::string path = make_keystore(dir);
    return path;
}

// Another lab's keystore: the same identities, each consistent with its own CA, none with ours.
const std::string& foreign_keystore() {
    static dw::test::TempDir dir;
    static const std::string path = make_keystore(dir);
    return path;
}

dw::dds::DdsConfig secure(const std::string& identity) {
    dw::dds::DdsConfig c;
    c.domain = dw::test::test_domain();
    c.ns = "sec" + std::to_string(::getpid());
    c.security = keystore();
    c.identity = identity;
    return c;
}

unsigned mode_of(const std::string& path) {
    struct stat st {};
    ::stat(path.c_str(), &st);
    return st.st_mode & 0777;
}

}  // namespace

TEST(Keystore, MakesACaAndOneSignedIdentityPerRoleWithPrivateKeys) {
    const dw::dds::KeystorePaths k{keystore()};
    EXPECT_EQ(mode_of(k.ca_key()), 0600u);
    const auto listing = dw::security::list_keystore(k.dir);
    ASSERT_EQ(listing.identities.size(), dw::dds::kRoles.size());
    for (const auto& i : listing.identities) {
        SCOPED_TRACE(i.name);
        EXPECT_TRUE(i.verifies);
        EXPECT_EQ(mode_of(k.key(i.name)), 0600u);
        EXPECT_EQ(i.subject, "/CN=" + i.name);
        const auto days =
            std::chrono::duration_cast<std::chrono::hours>(i.not_after - std::chrono::system_clock::now()).count() /
            24.0;
        EXPECT_NEAR(days, 30, 1);
    }
    std::string governance;
    ASSERT_TRUE(dw::dds::verify_signed(k.governance(), k.ca_cert(), &governance));
    EXPECT_NE(governance.find("<topic_expression>rt/*/vehicles/setpoint</topic_expression>"), std::string::npos);
    // What each identity may do is the registry's: the stand agent publishes the wrench, the
    // predictor does not; the operator commands the experiment.
    std::string stand, predictor, op;
    ASSERT_TRUE(dw::dds::verify_signed(k.permissions("stand_agent"), k.ca_cert(), &stand));
    ASSERT_TRUE(dw::dds::verify_signed(k.permissions("predictor"), k.ca_cert(), &predictor));
    ASSERT_TRUE(dw::dds::verify_signed(k.permissions("operator"), k.ca_cert(), &op));
    const auto publishes = [](const std::string& doc, const std::string& topic) {
        const auto pub = doc.find("<publish>"), end = doc.find("</publish>");
        const auto at = doc.find("<topic>rt/*/" + topic + "</topic>", pub);
        return at != std::string::npos && at < end;
    };
    EXPECT_TRUE(publishes(stand, "stand/wrench"));
    EXPECT_FALSE(publishes(predictor, "stand/wrench"));
    EXPECT_TRUE(publishes(op, "experiment/command"));
    EXPECT_FALSE(publishes(op, "vehicles/setpoint"));
}

TEST(Keystore, RerunningKeepsEveryIdentityAndAddsTheMissingOne) {
    const dw::dds::KeystorePaths k{keystore()};
    const std::string before = dw::read_file(k.cert("planner"), "cert");
    dw::security::KeystoreOptions o;
    o.dir = k.dir;
    o.identities = dw::security::role_identities();
    o.identities.push_back({"second_operator", dw::dds::Role::operator_});
    const auto r = dw::security::create_keystore(o);
    EXPECT_FALSE(r.new_ca);
    EXPECT_EQ(r.kept.size(), dw::dds::kRoles.size());
    ASSERT_EQ(r.created, std::vector<std::string>{"second_operator"});
    EXPECT_EQ(dw::read_file(k.cert("planner"), "cert"), before);
    EXPECT_TRUE(r.refreshed.empty()) << "nothing changed: nothing signed again";
    EXPECT_FALSE(r.refreshed_governance);
    o.identities = {{"../escape", dw::dds::Role::operator_}};
    EXPECT_THROW(dw::security::create_keystore(o), dw::InputError);
}

// A keystore made before a topic existed (vehicles/command, issue 69): a re-run of `dw-lab keys
// create` signs the governance and the permissions of the roles that use the topic again, and the
// planner may then publish it; nothing else changes.
TEST(Keystore, ARerunSignsAgainWhatTheLabsTopicsChanged) {
    dw::test::TempDir dir;
    const std::string copy = dir.file("keys");
    std::filesystem::copy(keystore(), copy, std::filesystem::copy_options::recursive);
    const dw::dds::KeystorePaths k{copy};
    const auto drop = [](std::string text) {  // as it was before vehicles/command
        for (std::size_t at; (at = text.find("vehicles/command")) != std::string::npos;) {
            const std::size_t from = text.rfind('\n', at), to = text.find('\n', at);
            text.erase(from, to - from);
        }
        return text;
    };
    const std::string planner = dw::read_file(k.permissions_xml("planner")),
                      stand = dw::read_file(k.permissions_xml("stand_agent"));
    ASSERT_NE(planner.find("vehicles/command"), std::string::npos);
    dw::write_file(k.permissions_xml("planner"), drop(planner));
    dw::security::sign_document(copy, drop(planner), k.permissions("planner"));
    dw::write_file(k.governance_xml(), drop(dw::read_file(k.governance_xml())));
    dw::security::sign_document(copy, drop(dw::read_file(k.governance_xml())), k.governance());
    dw::security::KeystoreOptions o;
    o.dir = copy;
    o.identities = dw::security::role_identities();
    const auto r = dw::security::create_keystore(o);
    EXPECT_TRUE(r.refreshed_governance);
    EXPECT_EQ(r.refreshed, std::vector<std::string>{"planner"});
    EXPECT_EQ(dw::read_file(k.permissions_xml("planner")), planner);
    EXPECT_EQ(dw::read_file(k.permissions_xml("stand_agent")), stand);
    std::string content;
    ASSERT_TRUE(dw::dds::verify_signed(k.permissions("planner"), k.ca_cert(), &content));
    EXPECT_NE(content.find("vehicles/command"), std::string::npos);
}

TEST(Keystore, ATamperedPermissionsFileDoesNotVerify) {
    dw::test::TempDir dir;
    const dw::dds::KeystorePaths k{keystore()};
    std::string text = dw::read_file(k.permissions("predictor"), "permissions");
    const auto at = text.find("rt/*/mocap/frame");
    ASSERT_NE(at, std::string::npos);
    text[at + 5] = 'n';  // one byte: mocap/frame -> nocap/frame
    dw::write_file(dir.file("tampered.p7s"), text);
    EXPECT_FALSE(dw::dds::verify_signed(dir.file("tampered.p7s"), k.ca_cert()));
    EXPECT_TRUE(dw::dds::verify_signed(k.permissions("predictor"), k.ca_cert()));
}

TEST(SecureDds, PermittedIdentitiesTalkAndAnOpenParticipantSeesNothing) {
    Participant stand(secure("stand_agent"), "stand_agent");
    Participant recorder(secure("recorder"), "recorder");
    auto open_config = secure("");
    open_config.security.clear();
    Participant stranger(open_config, "stranger");
    std::atomic<int> recorded{0}, overheard{0};
    dw::dds::Reader<dw::msg::WrenchStamped> r(recorder, topics::stand_wrench,
                                              [&](const auto&, const auto&) { ++recorded; });
    dw::dds::Reader<dw::msg::WrenchStamped> eavesdrop(stranger, topics::stand_wrench,
                                                      [&](const auto&, const auto&) { ++overheard; });
    dw::dds::Writer<dw::msg::WrenchStamped> w(stand, topics::stand_wrench);
    ASSERT_TRUE(w.wait_for_readers(1, 30000ms)) << "the recorder never matched the stand agent";
    // The crypto keys follow the match: a best-effort stream flows once they have arrived.
    const auto end = std::chrono::steady_clock::now() + 20s;
    std::uint64_t sent = 0;
    while (recorded < 20 && std::chrono::steady_clock::now() < end) {
        auto s = dw::probe::make_sample<dw::msg::WrenchStamped>(sent++);
        ASSERT_TRUE(w.write(s));
        std::this_thread::sleep_for(10ms);
    }
    EXPECT_GE(recorded.load(), 20);
    std::this_thread::sleep_for(500ms);
    EXPECT_EQ(overheard.load(), 0) << "a participant without the lab's keys read the wrench";
    EXPECT_EQ(w.matched(), 1) << "only the recorder matched";
}

// dw-probe without a keystore, on the lab's domain and namespace while the stand agent streams its
// wrench, sees no sample and times out; the same probe given the recorder's identity sees them (so
// the probe's silence is the keystore's doing, not a wrong domain or topic).
TEST(SecureDds, DwProbeWithoutAKeystoreSeesNothing) {
    dw::test::TempDir dir;
    Participant stand(secure("stand_agent"), "stand_agent");
    dw::dds::Writer<dw::msg::WrenchStamped> w(stand, topics::stand_wrench);
    std::atomic<bool> stop{false};
    std::thread stream([&] {
        for (std::uint64_t i = 0; !stop; ++i) {
            auto s = dw::probe::make_sample<dw::msg::WrenchStamped>(i);
            w.write(s);
            std::this_thread::sleep_for(10ms);
        }
    });
    const auto config = secure("recorder");
    auto probe = [&](std::vector<std::string> extra) {
        std::vector<std::string> argv{dw::test::bin("dw-probe"),
                                      "--domain",
                                      std::to_string(config.domain),
                                      "--namespace",
                                      config.ns,
                                      "--transport",
                                      "udp"};
        argv.insert(argv.end(), extra.begin(), extra.end());
        for (const char* a : {"echo", "stand/wrench", "--expect", "3", "--timeout", "8", "--quiet"}) argv.push_back(a);
        return dw::test::run(argv, dir, 60000ms);
    };
    const auto open = probe({});
    const auto permitted = probe({"--security", keystore(), "--identity", "recorder"});
    stop = true;
    stream.join();
    EXPECT_EQ(open.status, 1) << "a probe without the lab's keys: " << open.out << open.err;
    EXPECT_NE(open.out.find("timed out before every topic arrived"), std::string::npos) << open.out;
    EXPECT_EQ(permitted.status, 0) << "the recorder's identity: " << permitted.out << permitted.err;
}

// Any lab identity may publish heartbeats (every role produces them), so the permissions cannot
// stop one process's identity speaking for another; the launcher's status line shows who spoke
// (lab/launcher.cpp): the identity of the participant that sent each process's heartbeat.
TEST(SecureDds, TheIdentityBehindEachHeartbeatIsKnown) {
    Participant launcher(secure("launcher"), "launcher");
    dw::dds::PeerMonitor peers(launcher);
    Participant planner(secure("planner"), "planner");
    Participant impostor(secure("predictor"), "stand_agent");  // the predictor's keys, the stand agent's name
    dw::dds::Heartbeat honest(planner, 100ms), forged(impostor, 100ms);
    const auto end = std::chrono::steady_clock::now() + 30s;
    while ((peers.identity("planner").empty() || peers.identity("stand_agent").empty()) &&
           std::chrono::steady_clock::now() < end)
        std::this_thread::sleep_for(50ms);
    EXPECT_EQ(peers.identity("planner"), "planner");
    EXPECT_EQ(peers.identity("stand_agent"), "predictor") << "the heartbeat claims stand_agent; its sender is not";
    EXPECT_EQ(peers.identity("nobody"), "");
}

// A participant whose certificate another CA signed (a whole keystore of its own, valid in itself,
// so it starts) joins the running lab's domain: it authenticates with no lab participant, so its
// setpoints never reach the lab and it reads none of the lab's wrenches, while the lab's own flow.
TEST(SecureDds, AParticipantFromAnotherCaReachesNothing) {
    Participant stand(secure("stand_agent"), "stand_agent"), recorder(secure("recorder"), "recorder");
    Participant bridge(secure("mocap_bridge"), "mocap_bridge");
    auto outsider = [](const std::string& identity) {
        auto c = secure(identity);
        c.security = foreign_keystore();
        return c;
    };
    Participant outside_planner(outsider("planner"), "planner"), outside_recorder(outsider("recorder"), "recorder");
    std::atomic<int> recorded{0}, overheard{0}, moved{0};
    dw::dds::Reader<dw::msg::WrenchStamped> r(recorder, topics::stand_wrench,
                                              [&](const auto&, const auto&) { ++recorded; });
    dw::dds::Reader<dw::msg::WrenchStamped> eavesdrop(outside_recorder, topics::stand_wrench,
                                                      [&](const auto&, const auto&) { ++overheard; });
    dw::dds::Reader<dw::msg::VehicleSetpoint> vehicles(bridge, topics::vehicle_setpoint,
                                                       [&](const auto&, const auto&) { ++moved; });
    dw::dds::Writer<dw::msg::WrenchStamped> w(stand, topics::stand_wrench);
    dw::dds::Writer<dw::msg::VehicleSetpoint> forged(outside_planner, topics::vehicle_setpoint);
    ASSERT_TRUE(w.wait_for_readers(1, 30000ms)) << "the recorder never matched the stand agent";
    const auto end = std::chrono::steady_clock::now() + 20s;
    for (std::uint64_t i = 0; recorded < 20 && std::chrono::steady_clock::now() < end; ++i) {
        auto wrench = dw::probe::make_sample<dw::msg::WrenchStamped>(i);
        auto setpoint = dw::probe::make_sample<dw::msg::VehicleSetpoint>(i);
        ASSERT_TRUE(w.write(wrench));
        forged.write(setpoint);
        std::this_thread::sleep_for(10ms);
    }
    EXPECT_GE(recorded.load(), 20) << "the lab's own samples did not flow";
    std::this_thread::sleep_for(500ms);
    EXPECT_EQ(overheard.load(), 0) << "a participant of another CA read the lab's wrench";
    EXPECT_EQ(moved.load(), 0) << "a participant of another CA reached the vehicles";
    EXPECT_EQ(w.matched(), 1) << "only the recorder matched the stand agent";
    EXPECT_EQ(forged.matched(), 0) << "a lab reader matched a writer of another CA";
}

// A copy of the lab's keystore in which the planner's certificate, signed by the lab's CA as
// before, expired yesterday.
std::string keystore_with_expired_planner(const dw::test::TempDir& dir) {
    const std::string copy = dir.file("expired-keys");
    std::filesystem::copy(keystore(), copy, std::filesystem::copy_options::recursive);
    const dw::dds::KeystorePaths k{copy};
    auto read = [](const std::string& path) { return dw::ssl::Bio(BIO_new_file(path.c_str(), "r")); };
    const dw::ssl::Cert cert(PEM_read_bio_X509(read(k.cert("planner")).get(), nullptr, nullptr, nullptr));
    const dw::ssl::Key ca_key(PEM_read_bio_PrivateKey(read(k.ca_key()).get(), nullptr, nullptr, nullptr));
    if (!cert || !ca_key) return {};
    X509_gmtime_adj(X509_getm_notBefore(cert.get()), -2 * 86400L);
    X509_gmtime_adj(X509_getm_notAfter(cert.get()), -86400L);
    if (X509_sign(cert.get(), ca_key.get(), EVP_sha256()) <= 0) return {};
    const dw::ssl::Bio out(BIO_new_file(k.cert("planner").c_str(), "w"));
    return out && PEM_write_bio_X509(out.get(), cert.get()) == 1 ? copy : std::string();
}

// A setpoint writer made with Fast DDS alone, its security properties given as they are (without
// the lab's keystore check, which an attacker's program would not run).
class RawSetpointWriter {
public:
    explicit RawSetpointWriter(const std::string& keystore_dir) {
        auto config = secure("planner");
        config.security.clear();
        config.transport = dw::dds::Transport::udp;
        auto qos = dw::dds::participant_qos(config, "planner");
        for (auto& [name, value] : dw::dds::security_properties(keystore_dir, "planner"))
            qos.properties().properties().emplace_back(name, value);
        auto* factory = eprosima::fastdds::dds::DomainParticipantFactory::get_instance();
        participant_ = factory->create_participant(static_cast<eprosima::fastdds::dds::DomainId_t>(config.domain), qos);
        if (!participant_) return;
        eprosima::fastdds::dds::TypeSupport type(new dw::dds::PubSubOf<dw::msg::VehicleSetpoint>::type());
        type.register_type(participant_);
        auto* topic = participant_->create_topic("rt/" + config.ns + "/" + std::string(topics::vehicle_setpoint.suffix),
                                                 type.get_type_name(), eprosima::fastdds::dds::TOPIC_QOS_DEFAULT);
        auto* publisher = participant_->create_publisher(eprosima::fastdds::dds::PUBLISHER_QOS_DEFAULT);
        if (topic && publisher)
            writer_ = publisher->create_datawriter(topic, dw::dds::writer_qos(topics::vehicle_setpoint.qos));
    }
    ~RawSetpointWriter() {
        if (!participant_) return;
        participant_->delete_contained_entities();
        eprosima::fastdds::dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
    }
    bool joined() const { return writer_ != nullptr; }
    void write(std::uint64_t i) {
        auto s = dw::probe::make_sample<dw::msg::VehicleSetpoint>(i);
        writer_->write(&s);
    }

private:
    eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
    eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
};

// Setpoints a raw writer with the keystore's planner gets to the vehicles' reader in `window`.
int setpoints_delivered(const std::string& keystore_dir, std::chrono::seconds window) {
    Participant bridge(secure("mocap_bridge"), "mocap_bridge");
    std::atomic<int> got{0};
    dw::dds::Reader<dw::msg::VehicleSetpoint> vehicles(bridge, topics::vehicle_setpoint,
                                                       [&](const auto&, const auto&) { ++got; });
    RawSetpointWriter w(keystore_dir);
    if (!w.joined()) return 0;  // Fast DDS refused the participant itself
    const auto end = std::chrono::steady_clock::now() + window;
    for (std::uint64_t i = 0; got < 5 && std::chrono::steady_clock::now() < end; ++i) {
        w.write(i);
        std::this_thread::sleep_for(10ms);
    }
    return got.load();
}

// An expired certificate, signed by the lab's CA, given straight to Fast DDS: its setpoints reach
// no vehicle; the same program with the valid certificate does reach them (so what stops the
// expired one is its expiry, not the raw writer). Measured: Fast DDS 2.9.1 refuses to create the
// participant (PKI-DH's validate_local_identity), so the lab's side of the handshake is not what
// is exercised here — a stack that skipped its own check would meet the lab's.
TEST(SecureDds, AnExpiredCertificateReachesNothingEvenPastTheKeystoreCheck) {
    dw::test::TempDir dir;
    const std::string expired = keystore_with_expired_planner(dir);
    ASSERT_FALSE(expired.empty()) << "could not re-sign the planner's certificate";
    auto checked = secure("planner");
    checked.security = expired;
    EXPECT_THROW(Participant(checked, "planner"), dw::InputError) << "the lab's own check refuses it first";
    const int valid = setpoints_delivered(keystore(), 20s), stale = setpoints_delivered(expired, 10s);
    EXPECT_GE(valid, 5) << "the raw writer with a valid certificate did not deliver";
    EXPECT_EQ(stale, 0) << "an expired certificate's setpoints reached the vehicles";
}

TEST(SecureDds, AnIdentityMayNotPublishWhatItsRoleDoesNotProduce) {
    Participant predictor(secure("predictor"), "predictor");
    EXPECT_THROW(dw::dds::Writer<dw::msg::WrenchStamped>(predictor, topics::stand_wrench), dw::RuntimeError);
    EXPECT_NO_THROW(dw::dds::Writer<dw::msg::WrenchPrediction>(predictor, topics::wrench_prediction));
}

// Issue 72: the viewer's identity reads every lab topic and may publish none — not even the
// heartbeat or a clock request every other role sends — and its hub shows every channel.
TEST(SecureDds, TheViewerReadsEveryTopicAndMayPublishNone) {
    Participant viewer(secure("viewer"), "viewer");
    EXPECT_THROW(dw::dds::Writer<dw::msg::ProcessStatus>(viewer, topics::process_status), dw::RuntimeError);
    EXPECT_THROW(dw::dds::Writer<dw::msg::ClockProbe>(viewer, topics::clock_request), dw::RuntimeError);
    EXPECT_THROW(dw::dds::Writer<dw::msg::ExperimentCommand>(viewer, topics::experiment_command), dw::RuntimeError);
    const dw::viewer::Hub hub(viewer);
    EXPECT_EQ(hub.channels().size(), static_cast<std::size_t>(topics::kTopicCount));
    const auto xml = dw::security::permissions_xml({"viewer", dw::dds::Role::viewer, {}, {}});
    EXPECT_EQ(xml.find("<publish>"), std::string::npos) << xml;
}

// Shared memory beside UDP made secure participants sometimes never authenticate (Fast DDS 2.9.1,
// docs/BENCHMARKS.md): under --security the default transport stays UDP alone (as it is for every
// participant now) and shm is refused.
TEST(SecureDds, TheDefaultTransportIsUdpAloneAndSharedMemoryIsRefused) {
    const auto qos = dw::dds::participant_qos(secure("planner"), "planner");
    ASSERT_EQ(qos.transport().user_transports.size(), 1u);
    EXPECT_TRUE(std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(
        qos.transport().user_transports[0]));
    auto c = secure("planner");
    c.transport = dw::dds::Transport::shm;
    try {
        dw::dds::participant_qos(c, "planner");
        ADD_FAILURE() << "shared memory accepted under DDS Security";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--transport udp"), std::string::npos) << e.what();
    }
}

TEST(SecureDds, AMissingKeystoreIsOneLineNamingIt) {
    auto c = secure("planner");
    c.security = "/nonexistent/keys";
    try {
        Participant p(c, "planner");
        ADD_FAILURE() << "joined without a keystore";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/keys"), std::string::npos) << e.what();
    }
    c = secure("nobody");
    EXPECT_THROW(Participant(c, "nobody"), dw::InputError);
}

TEST(SecureDds, ATamperedOrMismatchedKeystoreIsRefusedNamingTheFile) {
    dw::test::TempDir dir;
    const std::string copy = dir.file("keys");
    std::filesystem::copy(keystore(), copy, std::filesystem::copy_options::recursive);
    const dw::dds::KeystorePaths k{copy};
    auto c = secure("predictor");
    c.security = copy;
    auto refused = [&](const std::string& file) {
        try {
            Participant p(c, "predictor");
            ADD_FAILURE() << "joined with a bad " << file;
        } catch (const dw::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
        }
    };
    std::string text = dw::read_file(k.permissions("predictor"), "permissions");
    const auto at = text.find("rt/*/mocap/frame");
    ASSERT_NE(at, std::string::npos);
    text[at + 5] = 'n';  // one byte: subscribe to nocap/frame instead
    dw::write_file(k.permissions("predictor"), text);
    refused(k.permissions("predictor"));
    std::filesystem::copy_file(k.permissions("planner"), k.permissions("predictor"),
                               std::filesystem::copy_options::overwrite_existing);
    std::filesystem::copy_file(k.key("planner"), k.key("predictor"), std::filesystem::copy_options::overwrite_existing);
    refused(k.key("predictor"));  // another identity's key
}

// Issue 70: a permissions file signed by the lab's own CA but holding `<dds/>` crashed every process
// that started with it (SIGSEGV inside Fast DDS, nothing on stderr). What the CA signed is now
// checked before Fast DDS reads it: each malformed document is one error naming the file and line.
TEST(SecureDds, ASignedButMalformedDocumentIsRefusedBeforeFastDdsReadsIt) {
    dw::test::TempDir dir;
    const std::string copy = dir.file("keys");
    std::filesystem::copy(keystore(), copy, std::filesystem::copy_options::recursive);
    const dw::dds::KeystorePaths k{copy};
    const std::string good = dw::read_file(k.permissions_xml("predictor"));
    auto c = secure("predictor");
    c.security = copy;
    const auto refusal = [&](const std::string& doc, const std::string& text) -> std::string {
        dw::security::sign_document(copy, text, doc);
        try {
            Participant p(c, "predictor");
        } catch (const dw::InputError& e) {
            return e.what();
        }
        return "joined";
    };
    const auto replaced = [&](const std::string& from, const std::string& to) {
        std::string t = good;
        const auto at = t.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        return at == std::string::npos ? t : t.replace(at, from.size(), to);
    };
    const std::string perm = k.permissions("predictor");
    const std::vector<std::pair<std::string, std::string>> cases{
        {"<dds/>", "has no <permissions>"},
        {"<dds><permissions/></dds>", "has no <grant>"},
        {"not xml at all <", "not well-formed XML"},
        {replaced("<default>DENY</default>", "<default>MAYBE</default>"), "<default> is 'MAYBE'"},
        {replaced("rt/*/mocap/frame", "rt/*/nocap/frame"), "topic 'rt/*/nocap/frame' names no lab topic"},
        {replaced("CN=predictor", "CN=planner"), "no <grant> for this identity"},
        {std::regex_replace(good, std::regex("<not_after>[^<]*</not_after>"),
                            "<not_after>1999-01-01T00:00:00</not_after>"),
         "not valid now"},
        {replaced("<not_before>", "<not_before>soon"), "expected a date and time"},
    };
    for (const auto& [text, expected] : cases) {
        const std::string what = refusal(perm, text);
        EXPECT_NE(what.find(perm), std::string::npos) << what;
        EXPECT_NE(what.find(expected), std::string::npos) << what << "\n  expected: " << expected;
    }
    dw::security::sign_document(copy, good, perm);
    EXPECT_EQ(refusal(perm, good), "joined") << "the keystore's own permissions, signed again";
    const std::string gov = dw::read_file(k.governance_xml());
    EXPECT_NE(refusal(k.governance(), "<dds/>").find("has no <domain_access_rules>"), std::string::npos);
    std::string bad = gov;
    bad.replace(bad.find("<rtps_protection_kind>") + 22, 7, "LOUDLY");
    EXPECT_NE(refusal(k.governance(), bad).find("<rtps_protection_kind> is 'LOUDLY"), std::string::npos);
    // As a process: one line naming the file, exit 2 (it was a SIGSEGV).
    dw::security::sign_document(copy, gov, k.governance());
    dw::security::sign_document(copy, "<dds/>", perm);
    const auto r = dw::test::run(
        {dw::test::bin("dw-probe"), "--domain", std::to_string(c.domain), "--transport", "udp", "--security", copy,
         "--identity", "predictor", "echo", "stand/wrench", "--timeout", "1", "--quiet"},
        dir);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(perm), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

// Issue 70: an encrypted key.pem made OpenSSL prompt for its passphrase on the terminal, and the
// process waited there past SIGINT. It is now refused at once, naming the file.
TEST(SecureDds, AnEncryptedPrivateKeyIsRefusedWithoutAskingForAPassphrase) {
    dw::test::TempDir dir;
    const std::string copy = dir.file("keys");
    std::filesystem::copy(keystore(), copy, std::filesystem::copy_options::recursive);
    const dw::dds::KeystorePaths k{copy};
    const dw::ssl::Key key = dw::ssl::read_private_key(dw::read_file(k.key("predictor")));
    ASSERT_TRUE(key);
    dw::ssl::Bio out(BIO_new(BIO_s_mem()));
    char pass[] = "secret";
    ASSERT_EQ(PEM_write_bio_PKCS8PrivateKey(out.get(), key.get(), EVP_aes_256_cbc(), pass, 6, nullptr, nullptr), 1);
    char* bytes = nullptr;
    const long n = BIO_get_mem_data(out.get(), &bytes);
    dw::write_file(k.key("predictor"), std::string(bytes, static_cast<std::size_t>(n)));
    auto c = secure("predictor");
    c.security = copy;
    try {
        Participant p(c, "predictor");
        ADD_FAILURE() << "joined with an encrypted key";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find(k.key("predictor")), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("encrypted"), std::string::npos) << e.what();
    }
}

namespace {

// Every UDP datagram on the loopback interface while it is open (an AF_PACKET socket: root or
// CAP_NET_RAW). The bytes of frames, not parsed: the test only searches them.
class LoopbackCapture {
public:
    LoopbackCapture() {
        fd_ = ::socket(AF_PACKET, SOCK_RAW, htons(ETH_P_ALL));
        if (fd_ < 0) return;
        sockaddr_ll addr{};
        addr.sll_family = AF_PACKET;
        addr.sll_protocol = htons(ETH_P_ALL);
        addr.sll_ifindex = static_cast<int>(::if_nametoindex("lo"));
        timeval tv{0, 100000};
        ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
            ::close(fd_);
            fd_ = -1;
            return;
        }
        thread_ = std::thread([this] {
            std::vector<char> buf(65536);
            while (!stop_) {
                const ssize_t n = ::recv(fd_, buf.data(), buf.size(), 0);
                if (n > 0) {
                    std::lock_guard lock(m_);
                    bytes_.append(buf.data(), static_cast<std::size_t>(n));
                }
            }
        });
    }
    ~LoopbackCapture() {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
        if (fd_ >= 0) ::close(fd_);
    }
    bool ok() const { return fd_ >= 0; }
    bool contains(const std::string& needle) {
        std::lock_guard lock(m_);
        return bytes_.find(needle) != std::string::npos;
    }
    std::size_t size() {
        std::lock_guard lock(m_);
        return bytes_.size();
    }

private:
    int fd_ = -1;
    std::atomic<bool> stop_{false};
    std::thread thread_;
    std::mutex m_;
    std::string bytes_;
};

std::string bytes_of(double v) { return std::string(reinterpret_cast<const char*>(&v), sizeof v); }

// Fast DDS delivers between open participants of one process without the wire; while one of
// these lives (and no participant does when it is made or ends), it goes by the wire.
class ByTheWire {
public:
    ByTheWire() { set(eprosima::fastrtps::INTRAPROCESS_OFF); }
    ~ByTheWire() { set(eprosima::fastrtps::INTRAPROCESS_FULL); }

private:
    static void set(eprosima::fastrtps::IntraprocessDeliveryType t) {
        eprosima::fastrtps::LibrarySettingsAttributes s;
        s.intraprocess_delivery = t;
        eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(s);
    }
};

// Publishes samples from `writer_identity` to `reader_identity` over UDP only (shared memory
// would bypass the wire) until 20 have arrived; with `open`, without DDS Security.
template <class T, class Topic, class Fill>
int deliver(const std::string& writer_identity, const std::string& reader_identity, const Topic& topic, Fill fill,
            bool open = false) {
    auto wc = secure(writer_identity), rc = secure(reader_identity);
    if (open) wc.security = rc.security = {};
    const ByTheWire by_the_wire;
    wc.transport = rc.transport = dw::dds::Transport::udp;
    Participant a(wc, writer_identity), b(rc, reader_identity);
    std::atomic<int> got{0};
    dw::dds::Reader<T> r(b, topic, [&](const auto&, const auto&) { ++got; });
    dw::dds::Writer<T> w(a, topic);
    if (!w.wait_for_readers(1, 30000ms)) return 0;
    const auto end = std::chrono::steady_clock::now() + 20s;
    for (std::uint64_t i = 0; got < 20 && std::chrono::steady_clock::now() < end; ++i) {
        T s = dw::probe::make_sample<T>(i);
        fill(s);
        w.write(s);
        std::this_thread::sleep_for(10ms);
    }
    return got.load();
}

}  // namespace

// No topic carries plaintext on the wire: every message is encrypted (the governance protects each
// at the strongest any topic needs, security/policy.cpp), the sensor topics with the setpoints. The
// same sample sent without DDS Security is readable (which shows the capture sees the samples).
TEST(SecureDds, EncryptedTopicsAreNotReadableOnTheWire) {
    LoopbackCapture capture;
    if (!capture.ok()) GTEST_SKIP() << "no packet capture here (needs root or CAP_NET_RAW)";
    const double secret = 12345.678901, sensor = 8765.4321012, open = 5432.1098765;
    const int setpoints =
        deliver<dw::msg::VehicleSetpoint>("planner", "mocap_bridge", topics::vehicle_setpoint, [&](auto& s) {
            s.vehicle_id("needle-vehicle");
            s.position_m().x(secret);
        });
    ASSERT_EQ(setpoints, 20) << "the setpoints did not flow";
    const int wrenches = deliver<dw::msg::WrenchStamped>("stand_agent", "recorder", topics::stand_wrench,
                                                         [&](auto& s) { s.force_n().x(sensor); });
    ASSERT_EQ(wrenches, 20);
    const int open_wrenches = deliver<dw::msg::WrenchStamped>(
        "stand_agent", "recorder", topics::stand_wrench, [&](auto& s) { s.force_n().x(open); }, true);
    ASSERT_EQ(open_wrenches, 20);
    std::this_thread::sleep_for(200ms);
    ASSERT_GT(capture.size(), 10000u);
    EXPECT_TRUE(capture.contains(bytes_of(open))) << "the open wrench is readable: the capture works";
    EXPECT_FALSE(capture.contains(bytes_of(sensor))) << "a secure wrench in plaintext on the wire";
    EXPECT_FALSE(capture.contains(bytes_of(secret))) << "a setpoint's position in plaintext on the wire";
    EXPECT_FALSE(capture.contains("needle-vehicle")) << "a setpoint's vehicle id in plaintext on the wire";
}
