#include "security/policy.hpp"

#include <ctime>
#include <sstream>

#include "dds/config.hpp"
#include "dds/topics.hpp"

namespace dw::security {

namespace {

constexpr const char* kHeader = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";

// Protection is per RTPS message (rtps_protection_kind), at the strongest any topic of the
// registry needs: with one topic to encrypt, every message is encrypted (AES-GCM, which also
// authenticates it: no one without the lab's keys may forge one). Per message rather than per
// submessage (metadata_protection_kind) because Fast DDS 2.9.1's crypto plugin re-derives a
// session key for every protected unit it receives (measured: docs/BENCHMARKS.md, DDS Security). Topics
// then add no protection of their own: their rules keep the access control and say, beside each,
// what the topic needs and why (the registry's protection). Payloads are not protected a second
// time (data_protection_kind NONE): that only matters where samples pass through a relay, which
// the lab has none of; and Fast DDS 2.9.1 cannot decode a payload protected with SIGN anyway
// (every sample fails with "Error decoding encoded payload"; measured, tests/test_security.cpp).
dds::Protection strongest_needed() {
    dds::Protection p = dds::Protection::sign;
    dds::topics::for_each([&](const auto& t) {
        if (t.protection == dds::Protection::encrypt) p = dds::Protection::encrypt;
    });
    return p;
}
const char* kind(dds::Protection p) { return p == dds::Protection::encrypt ? "ENCRYPT" : "SIGN"; }
const char* needs(dds::Protection p) { return p == dds::Protection::encrypt ? "encrypted" : "signed"; }

// Every domain a lab may use (tests pick their own): the keystore is the lab's, not a domain's.
std::string domains() {
    return "<domains><id_range><min>0</min><max>" + std::to_string(dds::kMaxDomainId) + "</max></id_range></domains>";
}

std::string utc(std::chrono::system_clock::time_point t) {
    const std::time_t s = std::chrono::system_clock::to_time_t(t);
    std::tm tm{};
    gmtime_r(&s, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
    return buf;
}

// A topic rule: discovered, alive and read or written only by whom the permissions allow; no
// protection of its own (every message is protected, above).
std::string topic_rule(const std::string& expression) {
    return "        <topic_rule>\n          <topic_expression>" + expression + "</topic_expression>\n" +
           "          <enable_discovery_protection>true</enable_discovery_protection>\n"
           "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
           "          <enable_read_access_control>true</enable_read_access_control>\n"
           "          <enable_write_access_control>true</enable_write_access_control>\n"
           "          <metadata_protection_kind>NONE</metadata_protection_kind>\n"
           "          <data_protection_kind>NONE</data_protection_kind>\n        </topic_rule>\n";
}

}  // namespace

std::string topic_expression(std::string_view suffix) { return "rt/*/" + std::string(suffix); }

std::string governance_xml() {
    std::ostringstream o;
    o << kHeader << "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
      << "xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/"
         "omg_shared_ca_governance.xsd\">\n"
      << "  <domain_access_rules>\n    <domain_rule>\n      " << domains() << "\n"
      << "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
      << "      <enable_join_access_control>true</enable_join_access_control>\n"
      << "      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>\n"
      << "      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>\n"
      << "      <!-- every message: the strongest protection a topic below needs -->\n"
      << "      <rtps_protection_kind>" << kind(strongest_needed()) << "</rtps_protection_kind>\n"
      << "      <topic_access_rules>\n";
    dds::topics::for_each([&](const auto& t) {
        o << "        <!-- " << t.suffix << ": needs " << needs(t.protection) << ": " << t.protection_reason << " -->\n"
          << topic_rule(topic_expression(t.suffix));
    });
    o << "        <!-- anything else: access-controlled (the permissions deny it) -->\n"
      << topic_rule("*") << "      </topic_access_rules>\n    </domain_rule>\n  </domain_access_rules>\n</dds>\n";
    return o.str();
}

std::string permissions_xml(const Grant& g) {
    std::ostringstream pub, sub;
    dds::topics::for_each([&](const auto& t) {
        if (dds::has(t.producers, g.role)) pub << "            <topic>" << topic_expression(t.suffix) << "</topic>\n";
        if (dds::has(t.consumers, g.role)) sub << "            <topic>" << topic_expression(t.suffix) << "</topic>\n";
    });
    std::ostringstream o;
    o << kHeader << "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
      << "xsi:noNamespaceSchemaLocation=\"http://www.omg.org/spec/DDS-SECURITY/20170901/"
         "omg_shared_ca_permissions.xsd\">\n"
      << "  <permissions>\n    <grant name=\"" << g.identity << "\">\n"
      << "      <subject_name>CN=" << g.identity << "</subject_name>\n"
      << "      <validity><not_before>" << utc(g.not_before) << "</not_before><not_after>" << utc(g.not_after)
      << "</not_after></validity>\n"
      << "      <!-- role " << dds::role_name(g.role) << " -->\n"
      << "      <allow_rule>\n        " << domains() << "\n";
    // A role that only reads (the viewer) has no publish section: an empty one is no valid document.
    if (!pub.str().empty())
        o << "        <publish>\n          <topics>\n" << pub.str() << "          </topics>\n        </publish>\n";
    o << "        <subscribe>\n          <topics>\n"
      << sub.str() << "          </topics>\n        </subscribe>\n"
      << "      </allow_rule>\n      <default>DENY</default>\n    </grant>\n  </permissions>\n</dds>\n";
    return o.str();
}

}  // namespace dw::security
