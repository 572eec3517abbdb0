#pragma once
// OpenSSL objects owned by std::unique_ptr, for the files that speak OpenSSL (the DDS Security
// checks here, the keystore in security/).
#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>

#include <memory>
#include <string>

namespace dw::ssl {

template <class T, void (*Free)(T*)>
struct Deleter {
    void operator()(T* p) const { Free(p); }
};
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using Cert = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using Bio = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;
using Store = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;

// A PEM private key, never asking for a passphrase: OpenSSL's default prompts on the terminal and
// waits (issue 70: an encrypted key.pem held a process past SIGINT). An encrypted key reads as none.
inline Key read_private_key(const std::string& pem_text) {
    Bio b(BIO_new_mem_buf(pem_text.data(), static_cast<int>(pem_text.size())));
    const auto no_passphrase = [](char*, int, int, void*) { return 0; };
    return Key(PEM_read_bio_PrivateKey(b.get(), nullptr, no_passphrase, nullptr));
}
// Whether a PEM text holds an encrypted private key (PKCS#8 or the older Proc-Type header).
inline bool is_encrypted_key(const std::string& pem_text) { return pem_text.find("ENCRYPTED") != std::string::npos; }

}  // namespace dw::ssl
