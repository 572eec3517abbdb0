#include "security/keystore.hpp"

#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <filesystem>
#include <memory>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "dds/openssl.hpp"
#include "dds/security.hpp"
#include "security/policy.hpp"

namespace dw::security {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxDays = 36500;
constexpr unsigned kPrivate = 0600;

using namespace dw::ssl;

// OpenSSL's own reason for the last failure, in the error.
[[noreturn]] void fail(const std::string& what) {
    char buf[256] = "unknown reason";
    if (const unsigned long e = ERR_get_error()) ERR_error_string_n(e, buf, sizeof buf);
    throw RuntimeError(log::cat(what, ": ", buf));
}

std::string bio_text(BIO* b) {
    char* data = nullptr;
    const long n = BIO_get_mem_data(b, &data);
    return std::string(data, static_cast<std::size_t>(n));
}

Key new_key() {
    Key k(EVP_EC_gen("P-256"));
    if (!k) fail("cannot make an EC P-256 key");
    return k;
}

void add_ext(X509* x, X509* issuer, int nid, const char* value) {
    X509V3_CTX ctx;
    X509V3_set_ctx_nodb(&ctx);
    X509V3_set_ctx(&ctx, issuer, x, nullptr, nullptr, 0);
    X509_EXTENSION* ex = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value);
    if (!ex || !X509_add_ext(x, ex, -1)) fail("cannot add a certificate extension");
    X509_EXTENSION_free(ex);
}

// A certificate for `cn`'s key, signed by the issuer (itself for the CA).
Cert make_cert(const std::string& cn, EVP_PKEY* key, X509* issuer, EVP_PKEY* issuer_key, int days) {
    Cert x(X509_new());
    if (!x) fail("cannot make a certificate");
    X509_set_version(x.get(), 2);
    BIGNUM* serial = BN_new();
    if (!serial || !BN_rand(serial, 159, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY) ||
        !BN_to_ASN1_INTEGER(serial, X509_get_serialNumber(x.get())))
        fail("cannot draw a serial number");
    BN_free(serial);
    X509_gmtime_adj(X509_getm_notBefore(x.get()), 0);
    X509_gmtime_adj(X509_getm_notAfter(x.get()), static_cast<long>(days) * 86400L);
    X509_set_pubkey(x.get(), key);
    X509_NAME* name = X509_get_subject_name(x.get());
    X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC, reinterpret_cast<const unsigned char*>(cn.c_str()), -1, -1, 0);
    const bool ca = issuer == nullptr;
    X509_set_issuer_name(x.get(), ca ? name : X509_get_subject_name(issuer));
    X509* by = ca ? x.get() : issuer;
    add_ext(x.get(), by, NID_basic_constraints, ca ? "critical,CA:TRUE" : "critical,CA:FALSE");
    add_ext(x.get(), by, NID_key_usage,
            ca ? "critical,keyCertSign,cRLSign,digitalSignature" : "critical,digitalSignature,keyAgreement");
    if (!X509_sign(x.get(), ca ? key : issuer_key, EVP_sha256())) fail("cannot sign the certificate of " + cn);
    return x;
}

std::string pem(X509* x) {
    Bio b(BIO_new(BIO_s_mem()));
    if (!PEM_write_bio_X509(b.get(), x)) fail("cannot write a certificate");
    return bio_text(b.get());
}

std::string pem(EVP_PKEY* k) {
    Bio b(BIO_new(BIO_s_mem()));
    if (!PEM_write_bio_PrivateKey(b.get(), k, nullptr, nullptr, 0, nullptr, nullptr))
        fail("cannot write a private key");
    return bio_text(b.get());
}

Cert read_cert(const std::string& path) {
    const std::string text = read_file(path, "certificate");
    Bio b(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
    Cert x(PEM_read_bio_X509(b.get(), nullptr, nullptr, nullptr));
    if (!x) throw InputError(log::cat(path, ": not a PEM certificate"));
    return x;
}

Key read_key(const std::string& path) {
    const std::string text = read_file(path, "private key");
    if (is_encrypted_key(text)) throw InputError(log::cat(path, ": an encrypted private key (the lab's are not)"));
    Key k = read_private_key(text);
    if (!k) throw InputError(log::cat(path, ": not a PEM private key"));
    return k;
}

// S/MIME, detached, text: what `openssl smime -sign -text` writes and Fast DDS reads.
std::string smime_sign(const std::string& text, X509* cert, EVP_PKEY* key) {
    const int flags = PKCS7_DETACHED | PKCS7_STREAM | PKCS7_TEXT;
    Bio in(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
    Pkcs7 p7(PKCS7_sign(cert, key, nullptr, in.get(), flags));
    if (!p7) fail("cannot sign a document");
    Bio out(BIO_new(BIO_s_mem()));
    if (!SMIME_write_PKCS7(out.get(), p7.get(), in.get(), flags)) fail("cannot write a signed document");
    return bio_text(out.get());
}

// A certificate's validity bound as a time point (the epoch if it cannot be read).
std::chrono::system_clock::time_point time_of(const ASN1_TIME* t) {
    std::tm tm{};
    if (!ASN1_TIME_to_tm(t, &tm)) return {};
    return std::chrono::system_clock::from_time_t(timegm(&tm));
}
std::chrono::system_clock::time_point not_after(X509* x) { return time_of(X509_get0_notAfter(x)); }

// An identity's permissions, valid as long as its certificate: a re-run (refresh_permissions)
// derives the same document for the same role and topics.
std::string permissions_of(const IdentityRequest& id, X509* cert) {
    return permissions_xml({id.name, id.role, time_of(X509_get0_notBefore(cert)), not_after(cert)});
}

struct Ca {
    Cert cert;
    Key key;
};

// The keystore's CA: read from `have`, or made into `k` when it has none.
Ca ensure_ca(const dds::KeystorePaths& have, const dds::KeystorePaths& k, int days, bool& made) {
    made = !fs::exists(have.ca_cert());
    if (!made) return {read_cert(have.ca_cert()), read_key(have.ca_key())};
    Key key = new_key();
    Cert cert = make_cert("Downwash Lab CA", key.get(), nullptr, nullptr, days);
    write_file(k.ca_key(), pem(key.get()), kPrivate);
    write_file(k.ca_cert(), pem(cert.get()));
    return {std::move(cert), std::move(key)};
}

void make_identity(const dds::KeystorePaths& k, const Ca& ca, const IdentityRequest& id, int days) {
    Key key = new_key();
    Cert cert = make_cert(id.name, key.get(), ca.cert.get(), ca.key.get(), days);
    const std::string permissions = permissions_of(id, cert.get());
    write_file(k.key(id.name), pem(key.get()), kPrivate);
    write_file(k.permissions_xml(id.name), permissions);
    write_file(k.permissions(id.name), smime_sign(permissions, ca.cert.get(), ca.key.get()));
    write_file(k.cert(id.name), pem(cert.get()));  // last: an identity with a certificate is whole
}

// A kept identity's permissions as its role's topics are now (dds/topics.hpp: a topic added since
// the keystore was made), over its certificate's validity; true when they changed and were signed again.
bool refresh_permissions(const dds::KeystorePaths& have, const dds::KeystorePaths& k, const Ca& ca,
                         const IdentityRequest& id) {
    const Cert cert = read_cert(have.cert(id.name));
    const std::string now = permissions_of(id, cert.get());
    std::error_code ec;
    if (fs::exists(have.permissions_xml(id.name), ec) && read_file(have.permissions_xml(id.name)) == now) return false;
    write_file(k.permissions_xml(id.name), now);
    write_file(k.permissions(id.name), smime_sign(now, ca.cert.get(), ca.key.get()));
    return true;
}

void check(const KeystoreOptions& o) {
    if (o.dir.empty()) throw InputError("--keystore: empty path");
    if (o.days < 1 || o.days > kMaxDays)
        throw InputError(log::cat("--days: ", o.days, " is not in [1, ", kMaxDays, "]"));
    for (const auto& id : o.identities)
        if (!is_plain_name(id.name))
            throw InputError(log::cat("identity '", id.name, "': letters, digits, '_', '-' and '.' only"));
}

}  // namespace

std::vector<IdentityRequest> role_identities() {
    std::vector<IdentityRequest> v;
    for (const auto& r : dds::kRoles) v.push_back({std::string(r.name), r.role});
    return v;
}

KeystoreResult create_keystore(const KeystoreOptions& o) {
    check(o);
    const dds::KeystorePaths have{o.dir};
    StagedFolder staged(o.dir);  // every new file appears together, or none (a full disk, an error)
    const dds::KeystorePaths k{staged.path()};
    KeystoreResult r;
    const Ca ca = ensure_ca(have, k, o.days, r.new_ca);
    const std::string g = governance_xml();
    if (r.new_ca || !fs::exists(have.governance()) || !fs::exists(have.governance_xml()) ||
        read_file(have.governance_xml()) != g) {
        r.refreshed_governance = !r.new_ca && fs::exists(have.governance());
        write_file(k.governance_xml(), g);
        write_file(k.governance(), smime_sign(g, ca.cert.get(), ca.key.get()));
    }
    for (const auto& id : o.identities) {
        if (fs::exists(have.cert(id.name))) {
            r.kept.push_back(id.name);
            if (refresh_permissions(have, k, ca, id)) r.refreshed.push_back(id.name);
            continue;
        }
        make_identity(k, ca, id, o.days);
        r.created.push_back(id.name);
    }
    staged.commit();
    return r;
}

void sign_document(const std::string& dir, const std::string& text, const std::string& path) {
    const dds::KeystorePaths k{dir};
    const Cert cert = read_cert(k.ca_cert());
    const Key key = read_key(k.ca_key());
    write_file(path, smime_sign(text, cert.get(), key.get()));
}

KeystoreListing list_keystore(const std::string& dir) {
    const dds::KeystorePaths k{dir};
    if (!fs::is_directory(dir)) throw InputError(log::cat("--keystore: ", dir, ": no such folder"));
    const Cert ca = read_cert(k.ca_cert());
    KeystoreListing l;
    l.ca_not_after = not_after(ca.get());
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir + "/identities", ec)) {
        const std::string name = e.path().filename().string();
        if (!fs::exists(k.cert(name))) continue;
        const Cert c = read_cert(k.cert(name));
        char subject[256];
        X509_NAME_oneline(X509_get_subject_name(c.get()), subject, sizeof subject);
        const Key ca_pub(X509_get_pubkey(ca.get()));
        const bool cert_ok = X509_verify(c.get(), ca_pub.get()) == 1;
        ERR_clear_error();
        l.identities.push_back(
            {name, subject, not_after(c.get()), cert_ok && dds::verify_signed(k.permissions(name), k.ca_cert())});
    }
    std::sort(l.identities.begin(), l.identities.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    return l;
}

}  // namespace dw::security
