#pragma once
// Fitting a channel model to its target by non-linear least squares (Ceres, Levenberg–Marquardt)
// on the training samples, with parameter uncertainty from the Jacobian.
//
// Residual r_j = (prediction_j - target_j) / std(target) at every s-th training sample
// (s = FitOptions::stride; the model itself always runs at the full rate, so the fractional delay
// and the dynamics see every sample). Parameters are fitted as value / scale (ParamSpec::scale)
// so that they are O(1), within the ParamSpec bounds. The Jacobian is a central difference.
// Uncertainty: covariance = sigma^2 (J^T J)^+, sigma^2 = RSS / (m - p); reported as one standard
// deviation per parameter. Residuals of real records are coloured, so these are lower bounds.

#include <vector>

#include "identify/data.h"
#include "identify/model.h"

namespace rths::identify {

struct FitOptions {
  std::size_t stride = 1;
  int max_iterations = 60;
};

struct FitResult {
  ChannelModel model;               // with fitted parameters
  std::vector<double> std_errors;   // one per parameter, same units
  std::vector<double> prediction;   // over the whole record
  double train_error = 0.0;         // normalised_error over split.train
  double heldout_error = 0.0;       // normalised_error over split.heldout
  double cost = 0.0;                // final Ceres cost (training, at the stride)
};

// Fits every parameter of `start` jointly, starting from its current values.
FitResult fit_channel(const ChannelModel& start, const ChannelSignals& signals, const Split& split,
                      const FitOptions& options = {});

// Errors of a model as it stands (no fitting), with zero uncertainty.
FitResult evaluate_channel(const ChannelModel& model, const ChannelSignals& signals,
                           const Split& split);

}  // namespace rths::identify
