#include "util/crc32c.h"

#include <gtest/gtest.h>

#include <string>

namespace rths::util {
namespace {

// Published check values: the CRC catalogue's CRC-32/ISCSI check and RFC 3720 B.4's vectors.
TEST(Crc32c, MatchesThePublishedCheckValues) {
  EXPECT_EQ(crc32c("123456789"), 0xE3069283u);
  EXPECT_EQ(crc32c(std::string(32, '\0')), 0x8A9136AAu);
  EXPECT_EQ(crc32c(std::string(32, '\xff')), 0x62A8AB43u);
  std::string ascending;
  for (int i = 0; i < 32; ++i) ascending.push_back(static_cast<char>(i));
  EXPECT_EQ(crc32c(ascending), 0x46DD794Eu);
  EXPECT_EQ(crc32c(""), 0u);
}

TEST(Crc32c, ExtendingEqualsTheCrcOfTheWhole) {
  const std::string a = "run record ", b = "entry 42";
  EXPECT_EQ(crc32c_extend(crc32c(a), b.data(), b.size()), crc32c(a + b));
}

TEST(Crc32c, EverySingleBitFlipChangesIt) {
  std::string bytes = "a step entry of a run record, 40 bytes..";
  const std::uint32_t good = crc32c(bytes);
  for (std::size_t i = 0; i < bytes.size(); ++i)
    for (int bit = 0; bit < 8; ++bit) {
      bytes[i] = static_cast<char>(bytes[i] ^ (1 << bit));
      EXPECT_NE(crc32c(bytes), good) << "byte " << i << " bit " << bit;
      bytes[i] = static_cast<char>(bytes[i] ^ (1 << bit));
    }
}

}  // namespace
}  // namespace rths::util
