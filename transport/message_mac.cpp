#include "transport/message_mac.h"

// The low-level SHA-256 API (deprecated in OpenSSL 3, still OpenSSL's own code, SHA-NI included):
// its SHA256_CTX is a plain struct, so the keyed HMAC states are copied per message by assignment.
// EVP_MAC re-initialised per message (what this was before) duplicates provider contexts (two
// allocations) and walks the provider layers for each field: about 4x the cost once the loop's
// cache is cold (bench/mac_bench.cpp, docs/security.md).
#define OPENSSL_SUPPRESS_DEPRECATED
#include <openssl/crypto.h>
#include <openssl/sha.h>

#include <cstring>

namespace rths::transport {

namespace {

// Little-endian, fixed width, so the encoding is the same on every host.
template <class T>
unsigned char* put(unsigned char* at, T value) {
  auto u = static_cast<std::uint64_t>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) at[i] = static_cast<unsigned char>(u >> (8 * i));
  return at + sizeof(T);
}

constexpr char kTag[] = "rths-mac-2";  // its terminating zero included, as always (2: the GUID)
constexpr std::size_t kBlock = 64;     // SHA-256's block (bytes)

}  // namespace

// HMAC-SHA256 (RFC 2104) keyed once: the inner and outer states after the key's padded block.
struct MessageMac::Context {
  SHA256_CTX inner{}, outer{};

  explicit Context(const std::string& key) {
    unsigned char block[kBlock] = {};
    if (key.size() > kBlock)
      SHA256(reinterpret_cast<const unsigned char*>(key.data()), key.size(), block);
    else
      std::memcpy(block, key.data(), key.size());
    unsigned char pad[kBlock];
    for (std::size_t i = 0; i < kBlock; ++i) pad[i] = block[i] ^ 0x36;
    SHA256_Init(&inner);
    SHA256_Update(&inner, pad, kBlock);
    for (std::size_t i = 0; i < kBlock; ++i) pad[i] = block[i] ^ 0x5c;
    SHA256_Init(&outer);
    SHA256_Update(&outer, pad, kBlock);
    OPENSSL_cleanse(block, sizeof block);
    OPENSSL_cleanse(pad, sizeof pad);
  }
  ~Context() {
    OPENSSL_cleanse(&inner, sizeof inner);
    OPENSSL_cleanse(&outer, sizeof outer);
  }

  // The fields in the documented order: tag, direction, writer GUID (16 bytes), run id
  // (length-prefixed), node id, kind, step, sent_ns, echo_ns, payload (length-prefixed); the
  // fixed-width ones gathered in two buffers, so four updates per message.
  Mac compute(const MacInput& m, Direction direction) const {
    unsigned char head[sizeof kTag + 1 + sizeof(WriterGuid) + 4];
    std::memcpy(head, kTag, sizeof kTag);
    unsigned char* at = put(head + sizeof kTag, static_cast<std::uint8_t>(direction));
    std::memcpy(at, m.writer.data(), m.writer.size());
    put(at + m.writer.size(), static_cast<std::uint32_t>(m.run_id.size()));
    unsigned char middle[4 + 4 + 8 + 8 + 8 + 4];
    at = put(middle, m.node_id);
    at = put(at, m.kind);
    at = put(at, m.step);
    at = put(at, m.sent_ns);
    at = put(at, m.echo_ns);
    put(at, static_cast<std::uint32_t>(m.payload.size()));
    SHA256_CTX c = inner;
    SHA256_Update(&c, head, sizeof head);
    SHA256_Update(&c, m.run_id.data(), m.run_id.size());
    SHA256_Update(&c, middle, sizeof middle);
    SHA256_Update(&c, m.payload.data(), m.payload.size());
    unsigned char digest[SHA256_DIGEST_LENGTH];
    SHA256_Final(digest, &c);
    Mac out{};
    c = outer;
    SHA256_Update(&c, digest, sizeof digest);
    SHA256_Final(out.data(), &c);
    OPENSSL_cleanse(&c, sizeof c);
    return out;
  }
};

MessageMac::MessageMac(const std::string& key) : keyed_(std::make_unique<Context>(key)) {}

MessageMac::~MessageMac() = default;

Mac MessageMac::sign(const Message& message, std::int64_t sent_ns, Direction direction,
                     const WriterGuid& writer) const {
  return keyed_->compute(MacInput::of(message, sent_ns, writer), direction);
}

bool MessageMac::verify(const Message& message, const WriterGuid& writer, Direction direction,
                        const Mac& mac) const {
  return verify(MacInput::of(message, message.sent_ns, writer), direction, mac);
}

bool MessageMac::verify(const MacInput& fields, Direction direction, const Mac& mac) const {
  const Mac expected = keyed_->compute(fields, direction);
  return CRYPTO_memcmp(expected.data(), mac.data(), mac.size()) == 0;
}

}  // namespace rths::transport
