#include "identify/residual/robust.h"

#include <gtest/gtest.h>

namespace rths::identify {
namespace {

TEST(Robust, TheMedianIsTheUpperMiddleValueAndZeroWhenEmpty) {
  EXPECT_DOUBLE_EQ(median_of({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median_of({4.0, 1.0, 3.0, 2.0}), 3.0);
  EXPECT_DOUBLE_EQ(median_of({}), 0.0);
}

// One outlier moves neither; a normal sample's sigma is read as its standard deviation.
TEST(Robust, TheSigmaIsTheScaledMedianDeviationAboutTheCentre) {
  EXPECT_DOUBLE_EQ(robust_sigma({-1.0, 0.0, 1.0, 1e9, -1.0}, 0.0), 1.4826);
  EXPECT_DOUBLE_EQ(robust_sigma({5.0, 6.0, 7.0}, 6.0), 1.4826);
}

}  // namespace
}  // namespace rths::identify
