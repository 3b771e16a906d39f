#include "identify/fit/validation.h"

#include "core/metrics.h"
#include "identify/fit/evidence.h"

#include <cmath>
#include <stdexcept>

namespace rths::identify {
KFoldResult kfold(const ChannelModel& model, const ChannelSignals& signals, std::size_t folds,
                  const FitOptions& options,
                  const std::function<void(std::size_t folds_done)>& on_fold) {
  const std::size_t n = signals.size();
  if (folds < 2 || n / folds < 50) {
    throw std::invalid_argument("k-fold: need at least 2 folds of 50 samples (" +
                                std::to_string(n) + " samples, " + std::to_string(folds) +
                                " folds)");
  }
  KFoldResult out;
  const auto specs = model.specs(signal_scales(signals));
  for (const auto& s : specs) out.param_names.push_back(s.name);
  std::vector<std::vector<double>> values(specs.size());
  const double record_std = core::standard_deviation(signals.target);
  for (std::size_t f = 0; f < folds; ++f) {
    const std::size_t begin = f * n / folds, end = (f + 1) * n / folds;
    Split split;
    split.size = n;
    for (std::size_t i = 0; i < n; ++i)
      (i >= begin && i < end ? split.heldout : split.train).push_back(i);
    const FitResult fit = fit_channel(model, signals, split, options);
    // fit.heldout_error is by the block's own std; rescaled to the record's (same residual).
    const double block_std = core::standard_deviation(
        std::span<const double>(signals.target).subspan(begin, end - begin));
    const double to_record = record_std > 0.0 && block_std > 0.0 ? block_std / record_std : 1.0;
    out.block_errors.push_back(fit.heldout_error);
    out.heldout_errors.push_back(fit.heldout_error * to_record);
    const auto block = [&](const std::vector<double>& x) {
      return std::span<const double>(x).subspan(begin, end - begin);
    };
    out.noise_floors.push_back(
        noise_floor(block(signals.input), block(signals.target), signals.dt) * to_record);
    for (std::size_t p = 0; p < specs.size(); ++p) values[p].push_back(fit.model.params[p]);
    if (on_fold) on_fold(f + 1);
  }
  out.mean = core::mean(out.heldout_errors);
  out.spread = core::sample_standard_deviation(out.heldout_errors);
  for (const auto& v : values) {
    out.param_mean.push_back(core::mean(v));
    out.param_spread.push_back(core::sample_standard_deviation(v));
  }
  return out;
}

CrossRecordResult validate_on(const ChannelModel& model, const ChannelSignals& other,
                              const std::string& source) {
  ChannelModel carried = model;
  const auto specs = model.specs(signal_scales(other));
  carried.fixed.assign(specs.size(), true);
  for (std::size_t i = 0; i < specs.size(); ++i) carried.fixed[i] = !specs[i].record_specific;
  Split all;
  all.size = other.size();
  for (std::size_t i = 0; i < other.size(); ++i) all.train.push_back(i);
  all.heldout = all.train;
  CrossRecordResult out;
  out.source = source;
  out.fit = fit_channel(carried, other, all);
  out.error = out.fit.heldout_error;
  return out;
}

}  // namespace rths::identify
