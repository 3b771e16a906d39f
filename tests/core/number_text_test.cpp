#include "core/number_text.h"

#include <gtest/gtest.h>

#include <string>

namespace rths::core {
namespace {

TEST(FormatNumber, SixSignificantDigitsWithoutTrailingZeros) {
  EXPECT_EQ(format_number(0.014), "0.014");
  EXPECT_EQ(format_number(1e-5), "1e-05");
  EXPECT_EQ(format_number(14.25), "14.25");
  EXPECT_EQ(format_number(1234567.0), "1.23457e+06");
}

TEST(FormatNumber, TheGivenSignificantDigits) {
  EXPECT_EQ(format_number(14.25, 3), "14.2");
  EXPECT_EQ(format_number(0.58642, 3), "0.586");
  EXPECT_EQ(format_number(1234.0, 3), "1.23e+03");
  EXPECT_EQ(format_number(0.1, 17), "0.10000000000000001");
  EXPECT_EQ(std::stod(format_number(0.1 + 0.2, 17)), 0.1 + 0.2);
}

TEST(FormatPercent, AFractionAsAPercentageToTheGivenDigits) {
  EXPECT_EQ(format_percent(0.01234), "1.23 %");
  EXPECT_EQ(format_percent(0.5), "50 %");
  EXPECT_EQ(format_percent(0.383127, 4), "38.31 %");
  EXPECT_EQ(format_percent(0.0), "0 %");
}

TEST(ParseFinite, OneFiniteNumberOrNothing) {
  EXPECT_EQ(parse_finite("1e-3"), 1e-3);
  EXPECT_EQ(parse_finite("-.5"), -0.5);
  for (const char* bad : {"1.2.3", "nan", "inf", "", "3 m", " 3"})
    EXPECT_FALSE(parse_finite(bad).has_value()) << bad;
}

TEST(Printable, EscapesBytesAndCutsLongTokens) {
  EXPECT_EQ(printable("ok\x01"), "ok\\x01");
  EXPECT_EQ(printable(std::string(45, 'a')), std::string(40, 'a') + "...");
}

}  // namespace
}  // namespace rths::core
