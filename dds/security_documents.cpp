#include "dds/security_documents.hpp"

#include <fnmatch.h>
#include <tinyxml2.h>

#include <algorithm>
#include <array>
#include <ctime>
#include <string_view>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/config.hpp"
#include "dds/topics.hpp"

namespace dw::dds {

namespace {

using tinyxml2::XMLElement;

// The schemas' enumerations (OMG DDS Security 1.1, 9.4.1.2 and 9.4.1.3).
constexpr std::array<std::string_view, 4> kBooleans{"true", "false", "1", "0"};  // xs:boolean
constexpr std::array<std::string_view, 5> kProtectionKinds{"NONE", "SIGN", "ENCRYPT", "SIGN_WITH_ORIGIN_AUTHENTICATION",
                                                           "ENCRYPT_WITH_ORIGIN_AUTHENTICATION"};
constexpr std::array<std::string_view, 3> kBasicProtectionKinds{"NONE", "SIGN", "ENCRYPT"};
constexpr std::array<std::string_view, 2> kDefaults{"ALLOW", "DENY"};
constexpr const char* kTimeFormat = "%Y-%m-%dT%H:%M:%S";  // xs:dateTime, as the grant's validity holds it

// A document being checked: every refusal names its file and line.
struct Doc {
    const std::string& path;

    [[noreturn]] void refuse(const XMLElement* at, const std::string& what) const {
        throw InputError(
            log::cat("--security: ", path, at ? log::cat(": line ", at->GetLineNum()) : std::string(), ": ", what));
    }
    const XMLElement* child(const XMLElement* e, const char* name) const {
        const XMLElement* c = e->FirstChildElement(name);
        if (!c) refuse(e, log::cat("<", e->Name(), "> has no <", name, ">"));
        return c;
    }
    std::string text(const XMLElement* e) const {
        std::string s = e->GetText() ? e->GetText() : "";
        const auto blank = [](unsigned char c) { return std::isspace(c) != 0; };
        s.erase(s.begin(), std::find_if_not(s.begin(), s.end(), blank));
        s.erase(std::find_if_not(s.rbegin(), s.rend(), blank).base(), s.end());
        if (s.empty()) refuse(e, log::cat("<", e->Name(), "> is empty"));
        return s;
    }
    template <std::size_t N>
    void one_of(const XMLElement* e, const std::array<std::string_view, N>& allowed) const {
        const std::string t = text(e);
        if (std::find(allowed.begin(), allowed.end(), t) == allowed.end())
            refuse(e, log::cat("<", e->Name(), "> is '", t, "' (expected one of ", log::join(allowed, ", "), ")"));
    }
    long integer(const XMLElement* e, long lo, long hi) const {
        const std::string t = text(e);
        char* end = nullptr;
        const long v = std::strtol(t.c_str(), &end, 10);
        if (*end != '\0' || v < lo || v > hi)
            refuse(e, log::cat("<", e->Name(), "> is '", t, "' (expected an integer in [", lo, ", ", hi, "])"));
        return v;
    }
    std::time_t time(const XMLElement* e) const {
        const std::string t = text(e);
        std::tm tm{};
        const char* end = strptime(t.c_str(), kTimeFormat, &tm);
        if (!end)
            refuse(e, log::cat("<", e->Name(), "> is '", t, "' (expected a date and time, e.g. 2026-12-06T10:00:00)"));
        return timegm(&tm);
    }
};

// The document parsed, its root <dds>, and the root's one section.
const XMLElement* section(const Doc& d, tinyxml2::XMLDocument& x, const std::string& xml, const char* name) {
    if (x.Parse(xml.data(), xml.size()) != tinyxml2::XML_SUCCESS) {
        std::string why = x.ErrorName();  // "XML_ERROR_MISMATCHED_ELEMENT": "mismatched element"
        why = why.substr(why.rfind("XML_ERROR_") == 0 ? 10 : 0);
        std::transform(why.begin(), why.end(), why.begin(),
                       [](unsigned char ch) { return ch == '_' ? ' ' : static_cast<char>(std::tolower(ch)); });
        d.refuse(nullptr, log::cat("line ", x.ErrorLineNum(), ": not well-formed XML (", why, ")"));
    }
    const XMLElement* root = x.RootElement();
    if (!root || std::string_view(root->Name()) != "dds") d.refuse(root, "the root element is not <dds>");
    return d.child(root, name);
}

// <domains>: one or more <id> or <id_range> (min, and max not below it).
void check_domains(const Doc& d, const XMLElement* rule) {
    const XMLElement* domains = d.child(rule, "domains");
    int n = 0;
    for (const XMLElement* e = domains->FirstChildElement(); e; e = e->NextSiblingElement(), ++n) {
        const std::string_view name = e->Name();
        if (name == "id") {
            d.integer(e, 0, kMaxDomainId);
        } else if (name == "id_range") {
            const long lo = d.integer(d.child(e, "min"), 0, kMaxDomainId);
            if (const XMLElement* max = e->FirstChildElement("max")) d.integer(max, lo, kMaxDomainId);
        } else {
            d.refuse(e, log::cat("<domains> holds <", name, "> (expected <id> or <id_range>)"));
        }
    }
    if (n == 0) d.refuse(domains, "<domains> names no domain");
}

// A topic pattern names a lab topic when it matches one under the namespace it gives ("rt/*/..."
// or "rt/<ns>/..."; anything else is tried under the default namespace).
bool names_a_lab_topic(const std::string& pattern) {
    std::string ns(kDefaultNamespace);
    if (pattern.rfind("rt/", 0) == 0) ns = pattern.substr(3, pattern.find('/', 3) - 3);
    bool found = false;
    topics::for_each([&](const auto& t) {
        found = found || fnmatch(pattern.c_str(), ("rt/" + ns + "/" + std::string(t.suffix)).c_str(), 0) == 0;
    });
    return found;
}

// <allow_rule> or <deny_rule>: its domains, then <publish>, <subscribe> or <relay>, each with topics.
void check_rule(const Doc& d, const XMLElement* rule) {
    check_domains(d, rule);
    for (const XMLElement* e = rule->FirstChildElement(); e; e = e->NextSiblingElement()) {
        const std::string_view name = e->Name();
        if (name == "domains") continue;
        if (name != "publish" && name != "subscribe" && name != "relay")
            d.refuse(e,
                     log::cat("<", rule->Name(), "> holds <", name, "> (expected <publish>, <subscribe> or <relay>)"));
        const XMLElement* topics = d.child(e, "topics");
        const XMLElement* topic = d.child(topics, "topic");
        for (; topic; topic = topic->NextSiblingElement("topic")) {
            const std::string pattern = d.text(topic);
            if (!names_a_lab_topic(pattern)) d.refuse(topic, log::cat("topic '", pattern, "' names no lab topic"));
        }
    }
}

// One <grant>; true when it is the identity's (its subject), which must then be valid now.
bool check_grant(const Doc& d, const XMLElement* grant, const std::string& subject, std::time_t now) {
    if (!grant->Attribute("name")) d.refuse(grant, "<grant> has no name");
    const std::string who = d.text(d.child(grant, "subject_name"));
    const XMLElement* validity = d.child(grant, "validity");
    const std::time_t from = d.time(d.child(validity, "not_before")), to = d.time(d.child(validity, "not_after"));
    int rules = 0;
    for (const XMLElement* e = grant->FirstChildElement(); e; e = e->NextSiblingElement()) {
        const std::string_view name = e->Name();
        if (name == "allow_rule" || name == "deny_rule") check_rule(d, e), ++rules;
    }
    if (rules == 0) d.refuse(grant, "<grant> grants nothing: no <allow_rule> or <deny_rule>");
    d.one_of(d.child(grant, "default"), kDefaults);
    if (who != subject) return false;
    if (now < from || now > to) d.refuse(validity, log::cat("the grant for ", subject, " is not valid now"));
    return true;
}

}  // namespace

void check_permissions(const std::string& xml, const std::string& path, const std::string& subject,
                       std::chrono::system_clock::time_point now) {
    const Doc d{path};
    tinyxml2::XMLDocument x;
    const XMLElement* permissions = section(d, x, xml, "permissions");
    d.child(permissions, "grant");
    bool mine = false;
    for (const XMLElement* g = permissions->FirstChildElement("grant"); g; g = g->NextSiblingElement("grant"))
        mine = check_grant(d, g, subject, std::chrono::system_clock::to_time_t(now)) || mine;
    if (!mine) d.refuse(permissions, log::cat("no <grant> for this identity (subject_name ", subject, ")"));
}

void check_governance(const std::string& xml, const std::string& path) {
    const Doc d{path};
    tinyxml2::XMLDocument x;
    const XMLElement* rules = section(d, x, xml, "domain_access_rules");
    d.child(rules, "domain_rule");
    for (const XMLElement* r = rules->FirstChildElement("domain_rule"); r; r = r->NextSiblingElement("domain_rule")) {
        check_domains(d, r);
        for (const char* b : {"allow_unauthenticated_participants", "enable_join_access_control"})
            d.one_of(d.child(r, b), kBooleans);
        for (const char* k : {"discovery_protection_kind", "liveliness_protection_kind", "rtps_protection_kind"})
            d.one_of(d.child(r, k), kProtectionKinds);
        const XMLElement* topics = d.child(r, "topic_access_rules");
        for (const XMLElement* t = topics->FirstChildElement("topic_rule"); t;
             t = t->NextSiblingElement("topic_rule")) {
            d.text(d.child(t, "topic_expression"));
            for (const char* b : {"enable_discovery_protection", "enable_liveliness_protection",
                                  "enable_read_access_control", "enable_write_access_control"})
                d.one_of(d.child(t, b), kBooleans);
            d.one_of(d.child(t, "metadata_protection_kind"), kProtectionKinds);
            d.one_of(d.child(t, "data_protection_kind"), kBasicProtectionKinds);
        }
    }
}

}  // namespace dw::dds
