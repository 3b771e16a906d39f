// MAC benchmark (not a test): what the run secret's MAC costs per message, alone. Signs and
// verifies --messages messages (payload --payload bytes: 48 is a Command's size, the commonest
// message) with transport::MessageMac and with OpenSSL's EVP_MAC HMAC-SHA256 re-initialised for
// each message over the same encoding (what MessageMac did before 2026-11-27), alternating the
// two --rounds times in one process. Prints per round the ns per sign and per verify, then the
// medians and the ratio MessageMac / EVP_MAC. Both must give the same MAC (checked each round).
// Then the same cold, as a paced loop meets it once per period: before each message 16 MiB are
// written (the caches and TLB filled with other data), and only the MAC is timed: the median ns
// per sign over --cold messages each. Last, what the receiver adds per message to find the
// sending writer's GUID for the MAC (transport/writer_guids.h): a lookup among --writers known
// writers (the last one added, the worst case), median ns of --rounds rounds.
//
//   rths_mac_bench [--messages N (default 200000)] [--payload BYTES] [--rounds R (default 7)]
//                  [--cold N (default 2000)] [--writers W (default 4)]
#include <openssl/core_names.h>
#include <openssl/evp.h>
#include <openssl/params.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "transport/message_mac.h"
#include "transport/writer_guids.h"

namespace {

using namespace rths::transport;

// The former implementation: one EVP_MAC context keyed once, EVP_MAC_init(no key) per message,
// one EVP_MAC_update per field.
class EvpMac {
 public:
  explicit EvpMac(const std::string& key) {
    mac_ = EVP_MAC_fetch(nullptr, "HMAC", nullptr);
    ctx_ = EVP_MAC_CTX_new(mac_);
    char digest[] = "SHA256";
    const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(OSSL_MAC_PARAM_DIGEST, digest, 0),
                                 OSSL_PARAM_END};
    EVP_MAC_init(ctx_, reinterpret_cast<const unsigned char*>(key.data()), key.size(), params);
  }
  ~EvpMac() {
    EVP_MAC_CTX_free(ctx_);
    EVP_MAC_free(mac_);
  }
  Mac compute(const Message& m, std::int64_t sent_ns, Direction direction,
              const WriterGuid& writer) {
    Mac out{};
    EVP_MAC_init(ctx_, nullptr, 0, nullptr);
    static constexpr char kTag[] = "rths-mac-2";
    EVP_MAC_update(ctx_, reinterpret_cast<const unsigned char*>(kTag), sizeof kTag);
    put(static_cast<std::uint8_t>(direction));
    EVP_MAC_update(ctx_, writer.data(), writer.size());
    put(static_cast<std::uint32_t>(m.run_id.size()));
    EVP_MAC_update(ctx_, reinterpret_cast<const unsigned char*>(m.run_id.data()), m.run_id.size());
    put(m.node_id);
    put(m.kind);
    put(m.step);
    put(sent_ns);
    put(m.echo_ns);
    put(static_cast<std::uint32_t>(m.payload.size()));
    EVP_MAC_update(ctx_, reinterpret_cast<const unsigned char*>(m.payload.data()),
                   m.payload.size());
    std::size_t length = 0;
    EVP_MAC_final(ctx_, out.data(), &length, out.size());
    return out;
  }

 private:
  template <class T>
  void put(T value) {
    unsigned char bytes[sizeof(T)];
    auto u = static_cast<std::uint64_t>(value);
    for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = static_cast<unsigned char>(u >> (8 * i));
    EVP_MAC_update(ctx_, bytes, sizeof(T));
  }
  EVP_MAC* mac_ = nullptr;
  EVP_MAC_CTX* ctx_ = nullptr;
};

Message command(std::size_t payload) {
  Message m;
  m.run_id = "rths-20261127-012345-abcdef";
  m.node_id = 2;
  m.kind = 3;
  m.step = 1000;
  m.sent_ns = 1'790'000'000'000'000'000;
  m.echo_ns = 0;
  m.payload.assign(payload, '\x2a');
  return m;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double ns_per(int n, F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) f(i);
  return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
         n;
}

// The median ns of `f` over `n` calls, each after the caches were filled with other data.
template <class F>
double cold_ns(int n, std::vector<unsigned char>& thrash, F&& f) {
  std::vector<double> ns;
  for (int i = 0; i < n; ++i) {
    for (std::size_t b = 0; b < thrash.size(); b += 64) thrash[b] = static_cast<unsigned char>(i);
    const auto t0 = std::chrono::steady_clock::now();
    f(i);
    ns.push_back(
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ns.begin(), ns.end());
  return ns[ns.size() / 2];
}

// ns per find() of the newest of `writers` known writers, the median of `rounds` rounds.
double lookup_ns(int writers, int messages, int rounds) {
  WriterGuids guids;
  for (int w = 0; w < writers; ++w) guids.add(1000 + static_cast<std::uint64_t>(w), WriterGuid{});
  volatile std::uint64_t newest = static_cast<std::uint64_t>(1000 + writers - 1);
  std::vector<double> ns;
  unsigned found = 0;
  for (int r = 0; r < rounds; ++r)
    ns.push_back(ns_per(messages, [&](int) { found += guids.find(newest) != nullptr; }));
  if (found != static_cast<unsigned>(messages) * static_cast<unsigned>(rounds))
    std::fprintf(stderr, "the newest writer was not always found\n");
  return median(ns);
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

}  // namespace

int main(int argc, char** argv) {
  int messages = 200000, rounds = 7, cold = 2000, writers = 4;
  std::size_t payload = 48;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--messages")) messages = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--payload")) payload = std::strtoul(argv[i + 1], nullptr, 10);
    if (!std::strcmp(argv[i], "--rounds")) rounds = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--cold")) cold = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--writers")) writers = std::max(1, std::atoi(argv[i + 1]));
  }
  const std::string key(64, 'c');
  MessageMac ours(key);
  EvpMac evp(key);
  Message m = command(payload);
  WriterGuid guid{};
  for (std::size_t b = 0; b < guid.size(); ++b) guid[b] = static_cast<std::uint8_t>(b * 17 + 1);
  std::vector<double> our_sign, our_verify, evp_sign, evp_verify;
  unsigned sink = 0;
  for (int r = 0; r < rounds; ++r) {
    if (ours.sign(m, m.sent_ns, Direction::kDown, guid) !=
        evp.compute(m, m.sent_ns, Direction::kDown, guid)) {
      std::fprintf(stderr, "MessageMac and EVP_MAC disagree\n");
      return 1;
    }
    const Mac mac = ours.sign(m, m.sent_ns, Direction::kDown, guid);
    evp_sign.push_back(ns_per(messages, [&](int i) {
      m.step = i;
      sink += evp.compute(m, m.sent_ns, Direction::kDown, guid)[0];
    }));
    our_sign.push_back(ns_per(messages, [&](int i) {
      m.step = i;
      sink += ours.sign(m, m.sent_ns, Direction::kDown, guid)[0];
    }));
    m.step = 1000;
    our_verify.push_back(
        ns_per(messages, [&](int) { sink += ours.verify(m, guid, Direction::kDown, mac); }));
    evp_verify.push_back(ns_per(
        messages, [&](int) { sink += evp.compute(m, m.sent_ns, Direction::kDown, guid) == mac; }));
    std::printf("round %d: sign %.0f ns (EVP_MAC %.0f), verify %.0f ns (EVP_MAC %.0f)\n", r + 1,
                our_sign.back(), evp_sign.back(), our_verify.back(), evp_verify.back());
  }
  std::vector<unsigned char> thrash(16u << 20);
  std::vector<double> our_cold, evp_cold;
  for (int r = 0; r < 3; ++r) {
    evp_cold.push_back(cold_ns(
        cold, thrash, [&](int i) { sink += evp.compute(m, i, Direction::kDown, guid)[0]; }));
    our_cold.push_back(
        cold_ns(cold, thrash, [&](int i) { sink += ours.sign(m, i, Direction::kDown, guid)[0]; }));
  }
  std::printf(
      "=> cold (caches filled before each message), medians of 3 x %d: sign %.0f ns vs "
      "EVP_MAC %.0f ns (ratio %.2f)\n",
      cold, median(our_cold), median(evp_cold), median(our_cold) / median(evp_cold));
  std::printf(
      "=> medians of %d rounds of %d messages, payload %zu bytes (load average %s): sign %.0f ns "
      "vs EVP_MAC %.0f ns (ratio %.2f); verify %.0f ns vs %.0f ns (ratio %.2f)  [%u]\n",
      rounds, messages, payload, load_average().c_str(), median(our_sign), median(evp_sign),
      median(our_sign) / median(evp_sign), median(our_verify), median(evp_verify),
      median(our_verify) / median(evp_verify), sink % 2);
  std::printf("=> the writer's GUID found among %d known writers: %.1f ns a message\n", writers,
              lookup_ns(writers, messages, rounds));
  return 0;
}
