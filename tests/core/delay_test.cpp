#include "core/delay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <vector>

#include "core/metrics.h"

namespace rths::core {
namespace {

constexpr double kDt = 1e-3;

// Feeds u(t) = f(t) (and its velocity) through a stage for `steps` steps; returns the outputs.
template <class Signal, class Velocity>
std::vector<double> run(DelayStage& stage, int steps, Signal u, Velocity v, double dt = kDt) {
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    out.push_back(stage.step({t, u(t), v(t)}));
  }
  return out;
}

std::filesystem::path temp_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rths_delay_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path;
}

TEST(CommandHistory, InterpolatesAndHoldsOldestAndNewest) {
  CommandHistory history(0.01, kDt);
  history.push(0.0, 1.0);
  EXPECT_DOUBLE_EQ(history.at(-5.0), 1.0);
  history.push(kDt, 3.0);
  EXPECT_DOUBLE_EQ(history.at(0.25 * kDt), 1.5);
  EXPECT_DOUBLE_EQ(history.at(10.0), 3.0);
  // Overflow the ring: the oldest kept sample is held for older queries.
  for (int k = 2; k < 100; ++k) history.push(k * kDt, k);
  EXPECT_DOUBLE_EQ(history.at(98.5 * kDt), 98.5);
  const double held = history.at(0.0);
  EXPECT_GT(held, 80.0);  // an old value, not the first command: the ring is bounded
  EXPECT_DOUBLE_EQ(history.at(90.5 * kDt), 90.5);
  history.clear();
  history.push(1.0, 7.0);
  EXPECT_DOUBLE_EQ(history.at(0.5), 7.0);
}

TEST(TimeShift, NonIntegerDelayInterpolatesRamp) {
  // A ramp is reproduced exactly by linear interpolation: u_real(t) = t - tau after t = tau.
  constexpr double kDelay = 2.37e-3;
  TimeShift shift(kDelay, kDt);
  const auto out = run(
      shift, 50, [](double t) { return t; }, [](double) { return 1.0; });
  EXPECT_DOUBLE_EQ(out[0], 0.0);
  EXPECT_DOUBLE_EQ(out[2], 0.0);  // before t = tau: the first command is held
  for (int k = 3; k < 50; ++k) EXPECT_NEAR(out[k], k * kDt - kDelay, 1e-15) << k;
  EXPECT_DOUBLE_EQ(shift.nominal_delay(), kDelay);
}

TEST(TimeShift, ResetForgetsHistoryAndCloneIsIndependent) {
  TimeShift shift(5e-3, kDt);
  run(
      shift, 20, [](double t) { return t; }, [](double) { return 1.0; });
  auto copy = shift.clone();
  shift.reset();
  EXPECT_DOUBLE_EQ(shift.step({1.0, 42.0, 0.0}), 42.0);
  // The clone still holds the ramp history: 5 steps back from the newest sample.
  EXPECT_NEAR(copy->step({20 * kDt, 20 * kDt, 1.0}), 15 * kDt, 1e-15);
}

TEST(TimeShift, RejectsBadInput) {
  EXPECT_THROW(TimeShift(-1e-3, kDt), std::invalid_argument);
  EXPECT_THROW(TimeShift(1e-3, 0.0), std::invalid_argument);
}

TEST(Eq1, LeadAndLagSigns) {
  Eq1Lead lead(0.01);
  Eq1Lag lag(0.01);
  EXPECT_DOUBLE_EQ(lead.step({0.0, 1.0, 2.0}), 1.02);
  EXPECT_DOUBLE_EQ(lag.step({0.0, 1.0, 2.0}), 0.98);
  EXPECT_LT(lead.nominal_delay(), 0.0);
  EXPECT_GT(lag.nominal_delay(), 0.0);
}

TEST(Gain, ScalesOutput) {
  Eq1Lag lag(0.0);
  lag.set_gain(1.1);
  EXPECT_DOUBLE_EQ(lag.step({0.0, 2.0, 0.0}), 2.2);
}

TEST(FirstOrderActuator, StepResponseIsExactExponential) {
  constexpr double kTau = 0.02;
  FirstOrderActuator actuator(kTau, kDt);
  const auto out = run(
      actuator, 100, [](double) { return 1.0; }, [](double) { return 0.0; });
  for (int k = 0; k < 100; ++k) {
    EXPECT_NEAR(out[k], 1.0 - std::exp(-(k + 1) * kDt / kTau), 1e-12) << k;
  }
  EXPECT_THROW(FirstOrderActuator(0.0, kDt), std::invalid_argument);
}

// The delay of a slow sine through a stage, measured by cross-correlation (J1).
double measured_delay(DelayStage& stage, double frequency, double dt) {
  const int steps = static_cast<int>(std::round(8.0 / frequency / dt));
  const double w = 2.0 * std::numbers::pi * frequency;
  std::vector<double> in(steps), out(steps);
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    in[k] = std::sin(w * t);
    out[k] = stage.step({t, in[k], w * std::cos(w * t)});
  }
  // Skip the first two periods (start-up transient).
  const std::size_t skip = static_cast<std::size_t>(steps / 4);
  return j1_delay(std::span(in).subspan(skip), std::span(out).subspan(skip), dt, 0.1);
}

TEST(TransferFunctionStage, FirstOrderLagMatchesContinuousFacts) {
  constexpr double kTau = 0.015;
  TransferFunctionStage lag({1.0}, {kTau, 1.0}, kDt, "1/(Ts+1)");
  EXPECT_DOUBLE_EQ(lag.dc_gain(), 1.0);
  EXPECT_DOUBLE_EQ(lag.nominal_delay(), kTau);
  // Low frequency (w T = 0.05): the phase delay atan(wT)/w equals T to 0.1 %.
  const double f = 0.05 / kTau / (2.0 * std::numbers::pi);
  EXPECT_NEAR(measured_delay(lag, f, kDt), kTau, 0.01 * kTau);
  // A lead-lag (s a + 1)/(s b + 1) has group delay b - a.
  TransferFunctionStage lead_lag({0.004, 1.0}, {0.010, 1.0}, kDt);
  EXPECT_NEAR(lead_lag.nominal_delay(), 0.006, 1e-15);
  // Unity steady state after a long step.
  const auto out = run(
      lag, 2000, [](double) { return 1.0; }, [](double) { return 0.0; });
  EXPECT_NEAR(out.back(), 1.0, 1e-12);
}

TEST(TransferFunctionStage, TustinOfSecondOrderKeepsDcGain) {
  // 4 / (s^2 + 2 s + 2): dc gain 2, group delay 1.
  TransferFunctionStage second({4.0}, {1.0, 2.0, 2.0}, 0.01);
  EXPECT_DOUBLE_EQ(second.dc_gain(), 2.0);
  EXPECT_DOUBLE_EQ(second.nominal_delay(), 1.0);
  const auto out = run(
      second, 3000, [](double) { return 1.0; }, [](double) { return 0.0; }, 0.01);
  EXPECT_NEAR(out.back(), 2.0, 1e-9);
}

TEST(TransferFunctionStage, RejectsImproperAndIntegrators) {
  EXPECT_THROW(TransferFunctionStage({1.0, 0.0, 0.0}, {1.0, 1.0}, kDt), std::invalid_argument);
  EXPECT_THROW(TransferFunctionStage({1.0}, {0.0, 1.0}, kDt), std::invalid_argument);
  EXPECT_THROW(TransferFunctionStage({1.0}, {1.0, 0.0}, kDt), std::invalid_argument);
  EXPECT_THROW(TransferFunctionStage({1.0}, {1.0, 1.0}, -kDt), std::invalid_argument);
}

TEST(BenchmarkActuator, DcGainNearOneAndLowFrequencyLagMatchesSimulation) {
  // Derived by hand from the plant's closed form (see delay.cpp):
  //   DC gain = a1b0 / (b2 a3 ke + a1b0),  group delay = d1 / d0 with
  //   d0 = b2 a3 ke + a1b0,  d1 = b1 a3 ke + b2 (ke + a3 ce + a2).
  constexpr double a1b0 = 2.13e13, a2 = 4.23e6, a3 = 3.3, b1 = 425.0, b2 = 1e5;
  constexpr double ce = 114.6, ke = 1.19e6;
  const double d0 = b2 * a3 * ke + a1b0;
  const double d1 = b1 * a3 * ke + b2 * (ke + a3 * ce + a2);
  for (double dt : {1e-3, 1.0 / 4096.0}) {
    auto plant = make_benchmark_actuator(dt);
    EXPECT_NEAR(plant->dc_gain(), a1b0 / d0, 1e-12);
    EXPECT_NEAR(plant->dc_gain(), 1.0, 0.05);
    EXPECT_NEAR(plant->nominal_delay(), d1 / d0, 1e-12);
    EXPECT_GT(plant->nominal_delay(), 2e-3);
    EXPECT_LT(plant->nominal_delay(), 40e-3);
    // The discretised plant, driven by a 0.5 Hz sine, lags by the continuous group delay.
    EXPECT_NEAR(measured_delay(*plant, 0.5, dt), plant->nominal_delay(), 0.5e-3) << dt;
    // And it settles to the DC gain (Tustin maps s = 0 to z = 1 exactly; what is left, ~5e-9 at
    // dt = 1/4096 s, is the rounding of direct-form coefficients with five poles near z = 1).
    plant->reset();
    const int steps = static_cast<int>(10.0 / dt);
    const auto out = run(
        *plant, steps, [](double) { return 1.0; }, [](double) { return 0.0; }, dt);
    EXPECT_NEAR(out.back(), plant->dc_gain(), 1e-7);
  }
}

TEST(JitterShift, DeterministicPerSeedBoundedAndResettable) {
  constexpr double kMean = 5e-3, kSd = 2e-3;
  JitterShift a(kMean, kSd, 42, kDt), b(kMean, kSd, 42, kDt), c(kMean, kSd, 43, kDt);
  std::vector<double> delays_a, out_a, out_b, out_c;
  double sum = 0.0;
  constexpr int kSteps = 20000;
  for (int k = 0; k < kSteps; ++k) {
    const double t = k * kDt;
    out_a.push_back(a.step({t, std::sin(t), std::cos(t)}));
    out_b.push_back(b.step({t, std::sin(t), std::cos(t)}));
    out_c.push_back(c.step({t, std::sin(t), std::cos(t)}));
    delays_a.push_back(a.last_delay());
    EXPECT_GE(a.last_delay(), 0.0);
    EXPECT_LE(a.last_delay(), kMean + 6 * kSd);
    sum += a.last_delay();
  }
  EXPECT_EQ(out_a, out_b);
  EXPECT_NE(out_a, out_c);
  EXPECT_NEAR(sum / kSteps, kMean, 0.05e-3);  // sd of the mean ~ 2e-3 / sqrt(2e4) = 1.4e-5
  a.reset();
  for (int k = 0; k < 100; ++k) {
    const double t = k * kDt;
    EXPECT_EQ(a.step({t, std::sin(t), std::cos(t)}), out_a[k]);
    EXPECT_EQ(a.last_delay(), delays_a[k]);
  }
}

TEST(TraceShift, FollowsTheTrace) {
  DelayTrace trace{{0.0, 1.0}, {2e-3, 2e-3}};
  TraceShift shift(trace, kDt);
  const auto out = run(
      shift, 30, [](double t) { return t; }, [](double) { return 1.0; });
  for (int k = 2; k < 30; ++k) EXPECT_NEAR(out[k], k * kDt - 2e-3, 1e-15);
  EXPECT_DOUBLE_EQ(shift.nominal_delay(), 2e-3);
}

TEST(DelayChain, ComposesCopiesDeeplyAndSumsDelays) {
  DelayChain chain;
  EXPECT_TRUE(chain.empty());
  EXPECT_EQ(chain.describe(), "none");
  EXPECT_DOUBLE_EQ(chain.step({0.0, 3.0, 0.0}), 3.0);
  chain.add(std::make_unique<TimeShift>(2e-3, kDt));
  chain.add(std::make_unique<TimeShift>(3e-3, kDt));
  EXPECT_DOUBLE_EQ(chain.nominal_delay(), 5e-3);
  std::vector<double> out;
  for (int k = 0; k < 20; ++k) out.push_back(chain.step({k * kDt, k * kDt, 1.0}));
  for (int k = 5; k < 20; ++k) EXPECT_NEAR(out[k], (k - 5) * kDt, 1e-15);
  DelayChain copy = chain;
  chain.reset();
  EXPECT_DOUBLE_EQ(chain.step({1.0, 9.0, 0.0}), 9.0);
  EXPECT_NEAR(copy.step({20 * kDt, 20 * kDt, 1.0}), 15 * kDt, 1e-15);
  EXPECT_NE(copy.describe().find("shift"), std::string::npos);
}

// A description names the block's own parameters to six significant digits, so that two chains
// whose lags differ by a fraction of a millisecond read apart.
TEST(DelayChain, DescribeNamesEachLagToSixDigits) {
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(0.01425, kDt));
  chain.add(std::make_unique<TimeShift>(0.0140001, kDt));
  EXPECT_EQ(chain.describe(), "shift(14.25 ms) -> shift(14.0001 ms)");
}

}  // namespace
}  // namespace rths::core
