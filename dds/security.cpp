#include "dds/security.hpp"

#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>

#include <filesystem>
#include <fstream>
#include <memory>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "dds/openssl.hpp"
#include "dds/security_documents.hpp"

namespace dw::dds {

namespace {

using namespace dw::ssl;

[[noreturn]] void refuse(const std::string& path, const std::string& what) {
    throw InputError(log::cat("--security: ", path, ": ", what));
}

Bio bio_of(const std::string& text) { return Bio(BIO_new_mem_buf(text.data(), static_cast<int>(text.size()))); }

Cert read_cert(const std::string& path) {
    const std::string text = read_file(path, "--security");
    Cert x(PEM_read_bio_X509(bio_of(text).get(), nullptr, nullptr, nullptr));
    ERR_clear_error();
    if (!x) refuse(path, "not a PEM certificate");
    return x;
}

// A certificate's subject as a grant's subject_name gives it (RFC 2253: "CN=planner").
std::string subject_of(const Cert& cert) {
    Bio out(BIO_new(BIO_s_mem()));
    X509_NAME_print_ex(out.get(), X509_get_subject_name(cert.get()), 0, XN_FLAG_RFC2253);
    char* bytes = nullptr;
    const long n = BIO_get_mem_data(out.get(), &bytes);
    return std::string(bytes, static_cast<std::size_t>(n));
}

// Fast DDS takes file URIs: file:// and the absolute path.
std::string uri_of(const std::string& path, const std::string& what) {
    std::error_code ec;
    const auto abs = std::filesystem::absolute(path, ec);
    if (ec || !std::filesystem::is_regular_file(abs) || !std::ifstream(abs).good())
        refuse(path, what + " missing or unreadable (dw-lab keys create makes it)");
    return "file://" + abs.string();
}

// The identity's certificate, key and signed documents, checked against the keystore's CA.
void check_identity(const KeystorePaths& k, const std::string& identity) {
    const Cert ca = read_cert(k.ca_cert()), cert = read_cert(k.cert(identity));
    const Key ca_key(X509_get_pubkey(ca.get()));
    if (X509_verify(cert.get(), ca_key.get()) != 1)
        refuse(k.cert(identity), "not signed by the keystore's CA (ca.cert.pem)");
    if (X509_cmp_current_time(X509_get0_notAfter(cert.get())) < 0)
        refuse(k.cert(identity), "expired (dw-lab keys list; make a new identity)");
    const std::string key_text = read_file(k.key(identity), "--security");
    if (is_encrypted_key(key_text))
        refuse(k.key(identity),
               "an encrypted private key: the lab's keys are not encrypted (no one is there to type a "
               "passphrase); make the identity again with dw-lab keys create");
    const Key key = read_private_key(key_text);
    if (!key || X509_check_private_key(cert.get(), key.get()) != 1)
        refuse(k.key(identity), "not the private key of cert.pem");
    std::string governance, permissions;
    for (const auto& [doc, content] : {std::pair{k.governance(), &governance}, {k.permissions(identity), &permissions}})
        if (!verify_signed(doc, k.ca_cert(), content))
            refuse(doc, "its signature does not verify against the keystore's CA (tampered, or from another keystore)");
    ERR_clear_error();
    // What was signed must also be what Fast DDS can read: a signed `<dds/>` crashed it.
    check_governance(governance, k.governance());
    check_permissions(permissions, k.permissions(identity), subject_of(cert), std::chrono::system_clock::now());
}

}  // namespace

bool verify_signed(const std::string& signed_file, const std::string& ca_cert, std::string* content) {
    const std::string text = read_file(signed_file, "signed document");
    BIO* data = nullptr;
    Pkcs7 p7(SMIME_read_PKCS7(bio_of(text).get(), &data));
    Bio owned(data);
    bool ok = false;
    if (p7) {
        const Cert ca = read_cert(ca_cert);
        Store store(X509_STORE_new());
        X509_STORE_add_cert(store.get(), ca.get());
        Bio out(BIO_new(BIO_s_mem()));
        ok = PKCS7_verify(p7.get(), nullptr, store.get(), data, out.get(), PKCS7_TEXT) == 1;
        if (ok && content) {
            char* bytes = nullptr;
            const long n = BIO_get_mem_data(out.get(), &bytes);
            content->assign(bytes, static_cast<std::size_t>(n));
        }
    }
    ERR_clear_error();
    return ok;
}

std::vector<std::pair<std::string, std::string>> security_properties(const std::string& dir,
                                                                     const std::string& identity) {
    if (!std::filesystem::is_directory(dir))
        throw InputError(log::cat("--security: ", dir, ": no such keystore folder"));
    const KeystorePaths k{dir};
    if (!std::filesystem::is_directory(k.identity_dir(identity)))
        refuse(k.identity_dir(identity), log::cat("no identity '", identity, "' in the keystore (dw-lab keys list)"));
    const std::string auth = "dds.sec.auth.builtin.PKI-DH.", access = "dds.sec.access.builtin.Access-Permissions.";
    return {
        {"dds.sec.auth.plugin", "builtin.PKI-DH"},
        {auth + "identity_ca", uri_of(k.ca_cert(), "the lab's CA certificate")},
        {auth + "identity_certificate", uri_of(k.cert(identity), "the identity's certificate")},
        {auth + "private_key", uri_of(k.key(identity), "the identity's private key")},
        {"dds.sec.access.plugin", "builtin.Access-Permissions"},
        {access + "permissions_ca", uri_of(k.ca_cert(), "the lab's CA certificate")},
        {access + "governance", uri_of(k.governance(), "the signed governance")},
        {access + "permissions", uri_of(k.permissions(identity), "the identity's signed permissions")},
        {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
    };
}

void add_security(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::string& dir,
                  const std::string& identity) {
    auto& p = qos.properties().properties();
    for (auto& [name, value] : security_properties(dir, identity)) p.emplace_back(name, value);
    check_identity(KeystorePaths{dir}, identity);
}

}  // namespace dw::dds
