#include "identify/fit/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

TEST(FitTest, RecoversDelayAndGainFromACoreTimeShift) {
  GeneratorSpec spec;
  spec.delay = 0.0137;
  spec.gain = 0.93;
  spec.displacement_noise = 5e-6;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kMeasured);
  const Split split = holdout_split(s.size(), 0.3);
  ChannelModel start = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  start.params = {1.0, 0.01};
  const FitResult fit = fit_channel(start, s, split);
  EXPECT_NEAR(fit.model.params[0], 0.93, 2e-3);
  EXPECT_NEAR(fit.model.params[1], 0.0137, 2e-4);
  // The truth lies within a few standard errors, and the errors are noise-sized.
  EXPECT_LT(std::abs(fit.model.params[1] - 0.0137), 5.0 * fit.std_errors[1] + 2e-5);
  EXPECT_GT(fit.std_errors[1], 0.0);
  EXPECT_LT(fit.heldout_error, 0.01);
  EXPECT_LT(fit.train_error, 0.01);
}

TEST(FitTest, LinearSpringWithUncertaintyThatShrinksWithNoise) {
  GeneratorSpec spec;
  spec.stiffness = 3.0e5;
  const auto fit_with_noise = [&](double noise) {
    spec.force_noise = noise;
    const MeasuredData data = generate_measured(spec);
    const ChannelSignals s = make_signals(data, Channel::kForce);
    const Split split = holdout_split(s.size(), 0.3);
    return fit_channel(declared_model(Channel::kForce, {Effect::kStiffness}, signal_scales(s)), s,
                       split);
  };
  const FitResult noisy = fit_with_noise(20.0), quiet = fit_with_noise(2.0);
  EXPECT_NEAR(noisy.model.params[0], 3.0e5, 3.0e3);
  EXPECT_NEAR(quiet.model.params[0], 3.0e5, 5.0e2);
  EXPECT_GT(noisy.std_errors[0], 5.0 * quiet.std_errors[0]);
}

TEST(FitTest, StrideFitsFewerResidualsButSameModel) {
  GeneratorSpec spec;
  spec.first_order_time_constant = 0.02;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kMeasured);
  const Split split = holdout_split(s.size(), 0.3);
  ChannelModel start = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  start = with_effect(start, Effect::kFirstOrder, std::vector<double>{0.01});
  start.params[1] = 0.01;
  FitOptions strided;
  strided.stride = 4;
  const FitResult fit = fit_channel(start, s, split, strided);
  EXPECT_NEAR(fit.model.params[2], 0.02, 5e-4);
  EXPECT_NEAR(fit.model.params[1], 0.012, 5e-4);
}

// A force that falls as the displacement grows: a spring can only match it with a negative
// stiffness, which its bound forbids; the fit says so instead of returning the artefact.
TEST(FitTest, ReportsAStiffnessTheDataWantNegative) {
  GeneratorSpec spec;
  MeasuredData data = generate_measured(spec);
  for (std::size_t i = 0; i < data.size(); ++i) data.force[i] = -1.0e5 * data.measured[i];
  const ChannelSignals s = make_signals(data, Channel::kForce);
  const Split split = holdout_split(s.size(), 0.3);
  const FitResult fit = fit_channel(
      declared_model(Channel::kForce, {Effect::kStiffness}, signal_scales(s)), s, split);
  EXPECT_GE(fit.model.params[0], 0.0);
  ASSERT_EQ(fit.bound_hits.size(), 1u);
  EXPECT_TRUE(fit.bound_hits[0].at_lower);
  EXPECT_EQ(fit.bound_hits[0].message(), "the data want a negative stiffness");
  // A positive spring is inside its bounds: nothing reported.
  for (std::size_t i = 0; i < data.size(); ++i) data.force[i] = 1.0e5 * data.measured[i];
  const ChannelSignals positive = make_signals(data, Channel::kForce);
  EXPECT_TRUE(
      fit_channel(declared_model(Channel::kForce, {Effect::kStiffness}, signal_scales(positive)),
                  positive, split)
          .bound_hits.empty());
}

TEST(FitTest, FixedParametersKeepTheirValue) {
  GeneratorSpec spec;
  spec.delay = 0.0137;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kMeasured);
  const Split split = holdout_split(s.size(), 0.3);
  ChannelModel start = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  start.params = {0.9, 0.01};
  start.fixed = {true, false};
  const FitResult fit = fit_channel(start, s, split);
  EXPECT_EQ(fit.model.params[0], 0.9);
  EXPECT_EQ(fit.std_errors[0], 0.0);
  EXPECT_NEAR(fit.model.params[1], 0.0137, 5e-4);
}

TEST(FitTest, EvaluateDoesNotChangeParameters) {
  GeneratorSpec spec;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kMeasured);
  const Split split = holdout_split(s.size(), 0.3);
  ChannelModel m = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  const FitResult r = evaluate_channel(m, s, split);
  EXPECT_EQ(r.model.params, m.params);
  EXPECT_GT(r.heldout_error, 0.05);  // no delay modelled: the 12 ms lag shows
}

}  // namespace
}  // namespace rths::identify
