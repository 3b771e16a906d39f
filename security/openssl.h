#pragma once
// RAII owners for the OpenSSL objects the security folder uses, and the one way it turns an
// OpenSSL failure into an exception: "<what>: <reason from the OpenSSL error queue>".
// Internal to security/ (pki.cpp, check.cpp); no other folder includes OpenSSL.

#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>

#include <filesystem>
#include <memory>
#include <string>

namespace rths::security::ossl {

template <auto Free>
struct Deleter {
  template <class T>
  void operator()(T* p) const {
    Free(p);
  }
};
using Bio = std::unique_ptr<BIO, Deleter<BIO_free_all>>;
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY_free>>;
using Cert = std::unique_ptr<X509, Deleter<X509_free>>;
using Store = std::unique_ptr<X509_STORE, Deleter<X509_STORE_free>>;
using StoreCtx = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX_free>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7_free>>;

// The oldest queued OpenSSL error as text ("unknown error" when the queue is empty); clears it.
std::string last_error();

// Throws std::runtime_error("<what>: <last_error()>") when `ok` is false.
void require(bool ok, const std::string& what);

// PEM readers; nullptr when the file is missing or holds no such object (last_error() says why).
Cert read_cert(const std::filesystem::path& file);
Key read_key(const std::filesystem::path& file);

// Everything a memory BIO holds, as a string.
std::string bio_text(BIO* bio);

// "2026-11-23T09:14:44" (UTC) for an ASN1 time; the form DDS permissions use for validity.
std::string iso_time(const ASN1_TIME* time);

}  // namespace rths::security::ossl
