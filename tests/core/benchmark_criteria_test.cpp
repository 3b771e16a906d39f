#include "core/benchmark_criteria.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace rths::core {
namespace {

constexpr double kDt = 1.0 / 4096.0;  // the benchmark's rate
constexpr int kSteps = 8192;

double wave(int k) {
  return std::sin(2 * std::numbers::pi * 1.7 * k * kDt) +
         0.3 * std::sin(2 * std::numbers::pi * 4.1 * k * kDt);
}

TEST(NormalisedStdError, RemovesTheMeanAsTheBenchmarkScriptDoes) {
  std::vector<double> ref, cmp;
  for (int k = 0; k < kSteps; ++k) {
    ref.push_back(wave(k));
    cmp.push_back(1.1 * wave(k) + 3.0);  // 10 % gain error plus an offset std() ignores
  }
  EXPECT_NEAR(normalised_std_error(ref, cmp), 10.0, 1e-9);
  EXPECT_THROW(normalised_std_error(ref, std::span(cmp).first(10)), std::invalid_argument);
}

TEST(BenchmarkCriteria, EachCriterionMeasuresItsOwnQuantity) {
  constexpr int kLag = 107;  // 26 ms at 4096 Hz: beyond the benchmark script's 50 samples
  // Three floors; storey 2 (index 1) experimental. Reference floors u0, u1, u2.
  Mat reference(kSteps, 3), response(kSteps, 3);
  std::vector<double> target(kSteps), measured(kSteps);
  for (int k = 0; k < kSteps; ++k) {
    reference(k, 0) = wave(k);
    reference(k, 1) = 2.0 * wave(k);
    reference(k, 2) = 2.5 * wave(k);
    response(k, 0) = 1.05 * reference(k, 0);  // floor 1: 5 % too large
    response(k, 1) = reference(k, 1);
    response(k, 2) = 0.8 * reference(k, 2);  // floor 3: 20 % too small
    target[k] = wave(k);                     // = the reference drift of storey 2 (u1 - u0)
    measured[k] = k >= kLag ? wave(k - kLag) : 0.0;
  }
  const BenchmarkCriteria c =
      benchmark_criteria(target, measured, response, reference, 1, kDt, 0.05);
  EXPECT_NEAR(c.J(1), kLag * kDt, 0.5 * kDt);
  EXPECT_DOUBLE_EQ(c.j1_search, 0.05);
  // A lag tau turns a sine of amplitude A into an error of amplitude 2 A sin(w tau / 2):
  // sqrt((0.278^2 + 0.3^2 0.660^2) / (1 + 0.3^2)) = 32.7 % (less the record's ends).
  EXPECT_NEAR(c.J(2), 32.7, 1.5);
  EXPECT_GT(c.J(3), 20.0);
  EXPECT_DOUBLE_EQ(c.J(4), c.J(2));  // the target is the reference drift here
  EXPECT_NEAR(c.J(6), 5.0, 1e-9);    // first other floor: floor 1
  EXPECT_NEAR(c.J(7), 20.0, 1e-9);   // second other floor: floor 3
  EXPECT_NEAR(c.J(8), 5.0, 1e-9);
  EXPECT_NEAR(c.J(9), 20.0, 1e-9);
  // Perfect tracking of the reference drift: J2..J5 vanish.
  const BenchmarkCriteria perfect =
      benchmark_criteria(target, target, response, reference, 1, kDt, 0.05);
  EXPECT_NEAR(perfect.J(1), 0.0, 1e-12);
  for (int j = 2; j <= 5; ++j) EXPECT_NEAR(perfect.J(j), 0.0, 1e-9) << "J" << j;
}

TEST(BenchmarkCriteria, SingleFloorHasNoOtherFloorCriteria) {
  Mat reference(100, 1), response(100, 1);
  std::vector<double> x(100);
  for (int k = 0; k < 100; ++k) x[k] = reference(k, 0) = response(k, 0) = wave(k);
  const BenchmarkCriteria c = benchmark_criteria(x, x, response, reference, 0, kDt, 0.01);
  for (int j = 6; j <= 9; ++j) EXPECT_TRUE(std::isnan(c.J(j))) << "J" << j;
  EXPECT_NE(format_criteria(c).find("J6 n/a"), std::string::npos);
  EXPECT_THROW(benchmark_criteria(x, x, response, reference, 1, kDt, 0.01), std::invalid_argument);
}

// Every criterion is named with its unit and a definition, in order, so that no report has to
// number an unnamed array; J1 is reported in ms.
TEST(BenchmarkCriteria, EveryCriterionIsNamedWithItsUnitAndDefinition) {
  const auto& definitions = criterion_definitions();
  for (int i = 0; i < 9; ++i) {
    const CriterionDefinition& d = definitions[static_cast<std::size_t>(i)];
    EXPECT_EQ(std::string(d.name), "J" + std::to_string(i + 1));
    EXPECT_EQ(std::string(d.unit), i == 0 ? "ms" : "%");
    EXPECT_GT(std::string(d.definition).size(), 10u) << d.name;
  }
  BenchmarkCriteria c;
  c.j = {0.0046, 10.4, 11.5, 36.1, 19.0, 32.3, 32.4, 14.8, 14.8};
  EXPECT_DOUBLE_EQ(reported_value(c, 1), 4.6);
  EXPECT_DOUBLE_EQ(reported_value(c, 5), 19.0);
  const std::string glossary = criteria_glossary();
  for (int i = 1; i <= 9; ++i)
    EXPECT_NE(glossary.find("J" + std::to_string(i) + " ("), std::string::npos) << glossary;
  EXPECT_NE(glossary.find("std(x_m - x_t) / std(x_t)"), std::string::npos) << glossary;
}

}  // namespace
}  // namespace rths::core
