#include "core/time_text.h"

#include <gtest/gtest.h>

namespace rths::core {
namespace {

TEST(FormatMs, ThreeSignificantDigitsInMilliseconds) {
  EXPECT_EQ(format_ms(0.014), "14 ms");
  EXPECT_EQ(format_ms(0.000586), "0.586 ms");
  EXPECT_EQ(format_ms(1.234), "1.23e+03 ms");
  EXPECT_EQ(format_ms(0.01425), "14.2 ms");
}

TEST(FormatMs, TheGivenSignificantDigits) {
  EXPECT_EQ(format_ms(0.01425, 6), "14.25 ms");
  EXPECT_EQ(format_ms(0.0140001, 6), "14.0001 ms");
}

}  // namespace
}  // namespace rths::core
