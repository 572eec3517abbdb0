#pragma once
// DDS Security for a lab process: where its files are in a keystore (made by `dw-lab keys`), and
// the participant properties that switch on Fast DDS's builtin plugins (PKI-DH authentication,
// Access-Permissions access control, AES-GCM-GMAC cryptography) with them.
//
// A keystore:
//   ca.cert.pem                      the lab's CA (it signs identities, governance, permissions)
//   private/ca.key.pem               its key (0600; only `dw-lab keys` needs it)
//   governance.xml, governance.p7s   the domain's rules, and the same signed (S/MIME)
//   identities/<name>/cert.pem       an identity's certificate (subject CN=<name>)
//   identities/<name>/key.pem        its private key (0600)
//   identities/<name>/permissions.xml, permissions.p7s   what it may publish and subscribe
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <string>
#include <utility>
#include <vector>

namespace dw::dds {

struct KeystorePaths {
    std::string dir;
    std::string ca_cert() const { return dir + "/ca.cert.pem"; }
    std::string ca_key() const { return dir + "/private/ca.key.pem"; }
    std::string governance_xml() const { return dir + "/governance.xml"; }
    std::string governance() const { return dir + "/governance.p7s"; }
    std::string identity_dir(const std::string& name) const { return dir + "/identities/" + name; }
    std::string cert(const std::string& name) const { return identity_dir(name) + "/cert.pem"; }
    std::string key(const std::string& name) const { return identity_dir(name) + "/key.pem"; }
    std::string permissions_xml(const std::string& name) const { return identity_dir(name) + "/permissions.xml"; }
    std::string permissions(const std::string& name) const { return identity_dir(name) + "/permissions.p7s"; }
};

// The properties that hand Fast DDS's builtin plugins `identity` of the keystore `dir` (its files
// as file:// URIs); throws dw::InputError naming a missing folder or file. Unchecked otherwise.
std::vector<std::pair<std::string, std::string>> security_properties(const std::string& dir,
                                                                     const std::string& identity);

// Adds the security properties for `identity` in the keystore `dir` to qos. Checks first what Fast
// DDS would refuse without saying why — a missing file, a certificate not signed by the
// keystore's CA or expired, a key that is not the certificate's, a governance or permissions
// document whose signature does not verify (tampered, or from another keystore) — and throws
// dw::InputError naming the file.
void add_security(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::string& dir,
                  const std::string& identity);

// Whether `signed_file` (S/MIME) is signed by the CA in `ca_cert`; its content when it is.
bool verify_signed(const std::string& signed_file, const std::string& ca_cert, std::string* content = nullptr);

}  // namespace dw::dds
