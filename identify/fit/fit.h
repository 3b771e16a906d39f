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
// Fixed parameters (ChannelModel::fixed, or declared fixed: ParamSpec::fixed) are held (Ceres
// SubsetManifold) and have no uncertainty. Bounds are the specs' (physical, narrowed by declarations).
// A bound hit: a free parameter that ends within 1e-6 (relative) of a bound while the gradient of
// the cost, J^T r, still points beyond it, i.e. the data want a value the bounds forbid.

#include <functional>
#include <string>
#include <vector>

#include "identify/model/data.h"
#include "identify/model/model.h"

namespace rths::identify {

struct FitOptions {
  std::size_t stride = 1;
  int max_iterations = 60;
  // The solver stops when an iteration changes the cost, or the parameters, by less than this
  // share (Ceres function_tolerance and parameter_tolerance).
  double tolerance = 1e-10;
  // Threads that simulate the Jacobian's columns (util::resolve_threads: <= 0 = every core).
  // The result does not depend on it.
  int threads = 0;
  // Called after every iteration of the solver (a heartbeat for progress); empty = none.
  std::function<void()> on_iteration;
};

struct BoundHit {
  std::size_t index = 0;  // in the model's params
  std::string name;       // parameter name
  bool at_lower = true;   // which bound
  double bound = 0.0;     // its value, SI
  std::string meaning;    // ParamSpec::below_means when at_lower, else ""
  // "the data want a negative stiffness" or "the data want time_constant above 1 s"
  std::string message() const;
};

struct FitResult {
  ChannelModel model;              // with fitted parameters
  std::vector<double> std_errors;  // one per parameter, same units
  std::vector<double> prediction;  // over the whole record
  double train_error = 0.0;        // normalised_error over split.train
  double heldout_error = 0.0;      // normalised_error over split.heldout
  double cost = 0.0;               // final Ceres cost (training, at the stride)
  std::vector<BoundHit> bound_hits;
};

// Fits every parameter of `start` jointly, starting from its current values.
FitResult fit_channel(const ChannelModel& start, const ChannelSignals& signals, const Split& split,
                      const FitOptions& options = {});

// A parameter estimated window by window: the record cut into `windows` contiguous windows, the
// parameter refitted alone on each (every other parameter fixed at the model's value), with its
// standard error from the Jacobian. Shows how a delay, a gain or a stiffness moves over a record.
struct WindowEstimate {
  double time = 0.0;       // s, centre of the window
  double value = 0.0;      // SI
  double std_error = 0.0;  // SI, one standard deviation
};
std::vector<WindowEstimate> windowed_estimate(const ChannelModel& model, std::size_t param_index,
                                              const ChannelSignals& signals, std::size_t windows);

// Errors of a model as it stands (no fitting), with zero uncertainty.
FitResult evaluate_channel(const ChannelModel& model, const ChannelSignals& signals,
                           const Split& split);

}  // namespace rths::identify
