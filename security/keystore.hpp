#pragma once
// The lab's keystore (layout: dds/security.hpp), made with the OpenSSL library: one CA (identity
// and permissions CA in one, ECDSA P-256), one identity per lab process (certificate + private key,
// written 0600), the signed governance and each identity's signed permissions (S/MIME, as Fast
// DDS and ROS 2's SROS2 read them). Re-running adds what is missing and never replaces an
// existing identity (its certificate and key); it signs its permissions again, and the governance,
// when the lab's topics have changed since (dds/topics.hpp), so that a keystore follows them.
#include <chrono>
#include <string>
#include <vector>

#include "dds/roles.hpp"

namespace dw::security {

struct IdentityRequest {
    std::string name;  // the certificate's CN and the identity's folder
    dds::Role role;
};

struct KeystoreOptions {
    std::string dir;
    std::vector<IdentityRequest> identities;
    int days = 365;  // every certificate and permission expires
};

struct KeystoreResult {
    std::vector<std::string> created, kept;  // identities
    // Kept identities whose permissions were signed again: their role's topics changed since.
    std::vector<std::string> refreshed;
    bool refreshed_governance = false;  // the same for the governance (a topic added)
    bool new_ca = false;
};

// Throws dw::InputError for a bad request (name, days, an unreadable keystore), dw::RuntimeError
// when OpenSSL or the disk fails.
KeystoreResult create_keystore(const KeystoreOptions& o);

struct IdentityStatus {
    std::string name;
    std::string subject;
    std::chrono::system_clock::time_point not_after;
    bool verifies = false;  // the certificate is signed by the keystore's CA, and its permissions too
};
struct KeystoreListing {
    std::chrono::system_clock::time_point ca_not_after;
    std::vector<IdentityStatus> identities;
};
KeystoreListing list_keystore(const std::string& dir);

// Signs `text` with the keystore's CA into `path`, as governance and permissions are signed (S/MIME).
// Throws dw::InputError when the keystore has no readable CA.
void sign_document(const std::string& dir, const std::string& text, const std::string& path);

// The default identities: one per lab role, named as the role.
std::vector<IdentityRequest> role_identities();

}  // namespace dw::security
