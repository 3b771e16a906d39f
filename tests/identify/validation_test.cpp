#include "identify/fit/validation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "identify/fit/evidence.h"
#include "identify/fit/identify.h"
#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

const std::filesystem::path kRealFile =
    std::filesystem::path(RTHS_DATA_DIR) / "measured/mts_mrdamper_chirp_0A.txt";

TEST(ValidationTest, KFoldRecoversAGeneratedTimeConstantWithSmallSpread) {
  GeneratorSpec spec;
  spec.first_order_time_constant = 0.015;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kMeasured);
  ChannelModel model = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  model = with_effect(model, Effect::kFirstOrder, std::vector<double>{0.01});
  const KFoldResult folds = kfold(model, s, 5);
  ASSERT_EQ(folds.heldout_errors.size(), 5u);
  EXPECT_LT(folds.mean, 0.01);
  EXPECT_LT(folds.spread, 0.005);
  EXPECT_NEAR(folds.param_mean[2], 0.015, 5e-4);
  EXPECT_GT(folds.param_spread[2], 0.0);
  // Each fold's noise floor is that of its own block: the generator's noise is the same
  // throughout, so every block's floor is near the record's, and no fold beats its floor by much.
  const double record_floor = noise_floor(s.input, s.target, s.dt);
  ASSERT_EQ(folds.noise_floors.size(), 5u);
  for (std::size_t f = 0; f < 5; ++f) {
    EXPECT_NEAR(folds.noise_floors[f], record_floor, 0.5 * record_floor) << f;
    EXPECT_GT(folds.heldout_errors[f], 0.7 * folds.noise_floors[f]) << f;
  }
  EXPECT_THROW(kfold(model, s, 1), std::invalid_argument);
}

// The same rig, another record with another sensor offset: the physical parameters carry over,
// the offset is re-estimated, and the error stays at the noise level.
TEST(ValidationTest, ModelCarriesToAnotherRecord) {
  GeneratorSpec spec;
  spec.first_order_time_constant = 0.015;
  spec.offset = 1e-4;
  const ChannelSignals first = make_signals(generate_measured(spec), Channel::kMeasured);
  ChannelModel model = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(first));
  model = with_effect(model, Effect::kFirstOrder, std::vector<double>{0.01});
  model = with_effect(model, Effect::kOffsetDrift, std::vector<double>{0.0, 0.0});
  const FitResult fit = fit_channel(model, first, holdout_split(first.size(), 0.3));
  spec.seed = 7;
  spec.offset = -2e-4;
  spec.command = GeneratorSpec::Command::kEarthquake;
  const ChannelSignals second = make_signals(generate_measured(spec), Channel::kMeasured);
  const CrossRecordResult other = validate_on(fit.model, second, "second");
  EXPECT_LT(other.error, 0.02);
  const auto sc = signal_scales(second);
  EXPECT_NEAR(other.fit.model.param(Effect::kOffsetDrift, "offset", sc).value(), -2e-4, 2e-5);
  EXPECT_EQ(other.fit.model.param(Effect::kFirstOrder, "time_constant", sc),
            fit.model.param(Effect::kFirstOrder, "time_constant", sc));
}

// Real MTS record, displacement channel: identified on the first half, k-fold over the whole
// record and the model carried to the second half. Issue 14's target: a k-fold spread (sample
// standard deviation of the folds' held-out errors, each normalised by the record's std) of at
// most 1 percentage point. Measured: whole record 3.40 +/- 0.25 %, active part 3.21 +/- 0.75 %.
// Before the errors were normalised by the record's std (each fold by its own block's std), the
// active part gave 3.69 +/- 1.18 %: the last fold (17-22 Hz, where the actuator realises a third
// of the command) had the same residual as the others (25-30 um) but a third of their std.
TEST(ValidationTest, RealActuatorKFoldAndSecondHalf) {
  const MeasuredData data = read_measured(kRealFile);
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  const Identification id = identify(data, options);
  const ChannelModel& model = id.channels.at(0).final_fit.model;
  FitOptions fast;
  fast.stride = 4;
  const KFoldResult folds = kfold(model, id.signals.at(0), 5, fast);
  std::cout << "k-fold held-out:";
  for (double e : folds.heldout_errors) std::cout << " " << e;
  std::cout << "  mean " << folds.mean << " spread " << folds.spread << "\n";
  EXPECT_LT(folds.mean, 0.05);
  EXPECT_LE(folds.spread, 0.01);

  // The record's active part (7.08 s to 59.18 s; data.h active_range).
  const ActiveRange active = active_range(data);
  const Identification trimmed = identify(slice(data, active.begin, active.end), options);
  const KFoldResult trimmed_folds =
      kfold(trimmed.channels.at(0).final_fit.model, trimmed.signals.at(0), 5, fast);
  std::cout << "active part: k-fold held-out:";
  for (std::size_t f = 0; f < 5; ++f) {
    std::cout << " " << trimmed_folds.heldout_errors[f] << " (floor "
              << trimmed_folds.noise_floors[f] << ", by the block's std "
              << trimmed_folds.block_errors[f] << ")";
  }
  std::cout << "  mean " << trimmed_folds.mean << " spread " << trimmed_folds.spread << "\n";
  EXPECT_LT(trimmed_folds.mean, 0.05);
  EXPECT_LE(trimmed_folds.spread, 0.01);
  for (std::size_t f = 0; f < 5; ++f) {
    EXPECT_GE(trimmed_folds.heldout_errors[f], trimmed_folds.noise_floors[f]) << f;
  }
  // By each block's own std the chirp's fast end would dominate: the same residual over a third
  // of the signal.
  EXPECT_EQ(trimmed_folds.block_errors.back(), *std::max_element(trimmed_folds.block_errors.begin(),
                                                                 trimmed_folds.block_errors.end()));
  EXPECT_LT(trimmed_folds.heldout_errors.back(), trimmed_folds.block_errors.back());

  const MeasuredData first = slice(data, 0, data.size() / 2);
  const MeasuredData second = slice(data, data.size() / 2, data.size());
  const Identification half = identify(first, options);
  const CrossRecordResult other = validate_on(
      half.channels.at(0).final_fit.model, make_signals(second, Channel::kMeasured), second.source);
  std::cout << "second half: " << other.error << "\n";
  EXPECT_LT(other.error, 0.08);
  EXPECT_THROW(slice(data, 10, 5), std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
