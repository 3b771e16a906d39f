#include "runtime/record/frame_scan.h"

#include <array>
#include <cstring>

#include "util/crc32c.h"

namespace rths::runtime {
namespace {

constexpr std::size_t kFrameHeaderBytes = 16;       // record.h: sync, size, two checksums
constexpr std::uint32_t kPolynomial = 0x82F63B78u;  // CRC-32C, reflected

std::uint32_t load_le32(const char* at) {
  std::uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | static_cast<std::uint8_t>(at[i]);
  return value;
}

// a(x) b(x) modulo the polynomial, both reflected (bit 31 is x^0): zlib's multmodp. @pre a != 0
constexpr std::uint32_t multiply_mod(std::uint32_t a, std::uint32_t b) {
  std::uint32_t m = 1u << 31, product = 0;
  for (;;) {
    if (a & m) {
      product ^= b;
      if ((a & (m - 1)) == 0) break;
    }
    m >>= 1;
    b = (b & 1u) ? (b >> 1) ^ kPolynomial : b >> 1;
  }
  return product;
}

// x^(2^k) modulo the polynomial, k = 0..63.
constexpr std::array<std::uint32_t, 64> make_powers() {
  std::array<std::uint32_t, 64> powers{};
  powers[0] = 1u << 30;  // x^1
  for (std::size_t k = 1; k < powers.size(); ++k)
    powers[k] = multiply_mod(powers[k - 1], powers[k - 1]);
  return powers;
}

constexpr std::array<std::uint32_t, 64> kPowers = make_powers();

// x^(8 n) modulo the polynomial: n bytes of shift. Never 0 (the polynomial has an x^0 term).
std::uint32_t byte_shift(std::uint64_t n) {
  std::uint32_t p = 1u << 31;  // x^0
  for (std::size_t k = 3; n != 0 && k < kPowers.size(); n >>= 1, ++k)
    if (n & 1u) p = multiply_mod(kPowers[k], p);
  return p;
}

}  // namespace

std::uint32_t crc32c_of_suffix(std::uint32_t crc_ab, std::uint32_t crc_a, std::uint64_t b_size) {
  return crc_ab ^ multiply_mod(byte_shift(b_size), crc_a);
}

bool FrameScanner::header_at(std::size_t at) {
  if (bytes_.size() - at < kFrameHeaderBytes) return false;
  const char* f = bytes_.data() + at;
  if (std::memcmp(f, kRecordFrameSync, sizeof kRecordFrameSync) != 0) return false;
  examined_ += 12;
  return load_le32(f + 12) == util::crc32c(f, 12);
}

Frame FrameScanner::frame_at(std::size_t at, std::uint32_t* size) {
  if (at >= bytes_.size() || !header_at(at)) return Frame::kNone;
  const char* f = bytes_.data() + at;
  *size = load_le32(f + 4);
  if (*size > bytes_.size() - at - kFrameHeaderBytes) return Frame::kCut;
  return load_le32(f + 8) == payload_crc(at + kFrameHeaderBytes, *size) ? Frame::kIntact
                                                                        : Frame::kDamaged;
}

std::size_t FrameScanner::next_frame(std::size_t from) {
  const std::string_view sync(reinterpret_cast<const char*>(kRecordFrameSync),
                              sizeof kRecordFrameSync);
  for (std::size_t at = bytes_.find(sync, from); at != std::string_view::npos;
       at = bytes_.find(sync, at + 1)) {
    if (header_at(at)) {
      examined_ += at - from;
      return at;
    }
  }
  if (from < bytes_.size()) examined_ += bytes_.size() - from;
  return std::string_view::npos;
}

// Bytes never checked before are checked directly, once; a payload over bytes already checked
// (or a short one) from the prefix checksums. The direct checks cover disjoint ranges: at most
// the record's size in all.
std::uint32_t FrameScanner::payload_crc(std::size_t first, std::size_t size) {
  const char* at = bytes_.data() + first;
  if (first >= checked_until_ || size <= kCheckpointBytes) {
    examined_ += size;
    if (first >= checked_until_) checked_until_ = first + size;
    return util::crc32c(at, size);
  }
  return crc32c_of_suffix(prefix_crc(first + size), prefix_crc(first), size);
}

std::uint32_t FrameScanner::prefix_crc(std::size_t end) {
  if (checkpoints_.empty()) {  // one pass over the record, the first time
    checkpoints_.reserve(bytes_.size() / kCheckpointBytes + 1);
    std::uint32_t crc = 0;
    checkpoints_.push_back(crc);
    for (std::size_t at = 0; at + kCheckpointBytes <= bytes_.size(); at += kCheckpointBytes)
      checkpoints_.push_back(crc = util::crc32c_extend(crc, bytes_.data() + at, kCheckpointBytes));
    examined_ += bytes_.size();
  }
  const std::size_t block = end / kCheckpointBytes, rest = end % kCheckpointBytes;
  examined_ += rest;
  return util::crc32c_extend(checkpoints_[block], bytes_.data() + block * kCheckpointBytes, rest);
}

}  // namespace rths::runtime
