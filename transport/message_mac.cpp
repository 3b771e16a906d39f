#include "transport/message_mac.h"

#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/params.h>

#include <stdexcept>

namespace rths::transport {

namespace {

// Little-endian, fixed width, so the encoding is the same on every host.
template <class T>
void put(EVP_MAC_CTX* ctx, T value) {
  unsigned char bytes[sizeof(T)];
  auto u = static_cast<std::uint64_t>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = static_cast<unsigned char>(u >> (8 * i));
  EVP_MAC_update(ctx, bytes, sizeof(T));
}

void put_bytes(EVP_MAC_CTX* ctx, const std::string& bytes) {
  put(ctx, static_cast<std::uint32_t>(bytes.size()));
  EVP_MAC_update(ctx, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
}

constexpr char kTag[] = "rths-mac-1";

}  // namespace

// One keyed HMAC-SHA256 context; EVP_MAC_init with no key starts it over under the same key.
struct MessageMac::Context {
  EVP_MAC* mac = nullptr;
  EVP_MAC_CTX* ctx = nullptr;

  explicit Context(const std::string& key) {
    mac = EVP_MAC_fetch(nullptr, "HMAC", nullptr);
    ctx = mac ? EVP_MAC_CTX_new(mac) : nullptr;
    char digest[] = "SHA256";
    const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(OSSL_MAC_PARAM_DIGEST, digest, 0),
                                 OSSL_PARAM_END};
    if (!ctx || EVP_MAC_init(ctx, reinterpret_cast<const unsigned char*>(key.data()), key.size(),
                             params) != 1) {
      release();
      throw std::runtime_error("OpenSSL has no HMAC-SHA256 for the run secret");
    }
  }
  ~Context() { release(); }
  void release() {
    EVP_MAC_CTX_free(ctx);
    EVP_MAC_free(mac);
    ctx = nullptr;
    mac = nullptr;
  }

  Mac compute(const Message& m, std::int64_t sent_ns, Direction direction) {
    Mac out{};
    EVP_MAC_init(ctx, nullptr, 0, nullptr);
    EVP_MAC_update(ctx, reinterpret_cast<const unsigned char*>(kTag), sizeof kTag);
    put(ctx, static_cast<std::uint8_t>(direction));
    put_bytes(ctx, m.run_id);
    put(ctx, m.node_id);
    put(ctx, m.kind);
    put(ctx, m.step);
    put(ctx, sent_ns);
    put(ctx, m.echo_ns);
    put_bytes(ctx, m.payload);
    std::size_t length = 0;
    EVP_MAC_final(ctx, out.data(), &length, out.size());
    return out;
  }
};

MessageMac::MessageMac(const std::string& key)
    : signer_(std::make_unique<Context>(key)), verifier_(std::make_unique<Context>(key)) {}

MessageMac::~MessageMac() = default;

Mac MessageMac::sign(const Message& message, std::int64_t sent_ns, Direction direction) {
  std::lock_guard lock(sign_mutex_);
  return signer_->compute(message, sent_ns, direction);
}

bool MessageMac::verify(const Message& message, Direction direction, const Mac& mac) {
  Mac expected;
  {
    std::lock_guard lock(verify_mutex_);
    expected = verifier_->compute(message, message.sent_ns, direction);
  }
  return CRYPTO_memcmp(expected.data(), mac.data(), mac.size()) == 0;
}

}  // namespace rths::transport
