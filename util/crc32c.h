#pragma once
// CRC-32C (Castagnoli; iSCSI, RFC 3720 B.4): polynomial 0x1EDC6F41, reflected (0x82F63B78),
// initial value and final XOR 0xFFFFFFFF. Check value: crc32c("123456789") = 0xE3069283.
// Detects every burst error up to 32 bits and, over a frame of random damage, misses 1 in 2^32.
// A table of 256 entries, built once at compile time; no hardware instruction is assumed.
//
//   crc32c(data, size)            the CRC of the bytes
//   crc32c_extend(crc, data, size) the CRC of (bytes already covered by `crc`) + these bytes, so
//                                  crc32c_extend(crc32c(a), b) == crc32c(a + b)

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace rths::util {

std::uint32_t crc32c_extend(std::uint32_t crc, const void* data, std::size_t size);

inline std::uint32_t crc32c(const void* data, std::size_t size) {
  return crc32c_extend(0, data, size);
}
inline std::uint32_t crc32c(std::string_view bytes) { return crc32c(bytes.data(), bytes.size()); }

}  // namespace rths::util
