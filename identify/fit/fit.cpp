#include "identify/fit/fit.h"

#include "util/parallel_for.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rths::identify {
namespace {

// One residual block over all training samples; the model is a recursive simulation, so the
// Jacobian comes from central differences of whole-record predictions.
class ChannelCost final : public ceres::CostFunction {
 public:
  ChannelCost(const ChannelModel& model, const ChannelSignals& signals, const Split& split,
              std::vector<double> scales, std::size_t stride, double target_scale, int threads)
      : model_(model),
        signals_(signals),
        scales_(std::move(scales)),
        stride_(stride),
        target_scale_(target_scale),
        threads_(threads) {
    for (std::size_t r = 0; r < split.train.size(); r += stride_)
      indices_.push_back(split.train[r]);
    set_num_residuals(static_cast<int>(indices_.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(scales_.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const std::size_t p = scales_.size();
    std::vector<double> physical(p);
    for (std::size_t i = 0; i < p; ++i) physical[i] = parameters[0][i] * scales_[i];
    const bool with_jacobian = jacobians != nullptr && jacobians[0] != nullptr;
    // Item 0 is the prediction at the parameters; items 2i+1 and 2i+2 shift parameter i up and
    // down by h_i (central difference). Each item is a whole-record simulation of its own, so
    // they run on threads_ threads; every value is the same whatever the threads.
    const std::size_t items = with_jacobian ? 2 * p + 1 : 1;
    std::vector<std::vector<double>> runs(items);
    const auto step = [&](std::size_t i) {
      return 1e-5 * std::max(1.0, std::abs(parameters[0][i]));
    };
    util::parallel_for(items, items > 1 ? threads_ : 1, [&](std::size_t item) {
      std::vector<double> shifted = physical;
      if (item > 0) {
        const std::size_t i = (item - 1) / 2;
        const double h = item % 2 == 1 ? step(i) : -step(i);
        shifted[i] = (parameters[0][i] + h) * scales_[i];
      }
      predict(model_, shifted, signals_, runs[item]);
    });
    const std::vector<double>& prediction = runs[0];
    for (std::size_t r = 0; r < indices_.size(); ++r) {
      const std::size_t j = indices_[r];
      residuals[r] = (prediction[j] - signals_.target[j]) / target_scale_;
      if (!std::isfinite(residuals[r])) return false;
    }
    if (!with_jacobian) return true;
    const std::size_t m = indices_.size();
    for (std::size_t i = 0; i < p; ++i) {
      const double h = step(i);
      const std::vector<double>& plus = runs[2 * i + 1];
      const std::vector<double>& minus = runs[2 * i + 2];
      for (std::size_t r = 0; r < m; ++r) {
        const std::size_t j = indices_[r];
        jacobians[0][r * p + i] = (plus[j] - minus[j]) / (2.0 * h * target_scale_);
      }
    }
    return true;
  }

 private:
  const ChannelModel& model_;
  const ChannelSignals& signals_;
  std::vector<double> scales_;
  std::size_t stride_;
  double target_scale_;
  int threads_;
  std::vector<std::size_t> indices_;
};

// FitOptions::on_iteration as a Ceres callback.
class Heartbeat final : public ceres::IterationCallback {
 public:
  explicit Heartbeat(const std::function<void()>& beat) : beat_(beat) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    beat_();
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::function<void()>& beat_;
};

double target_spread(const ChannelSignals& signals, const Split& split) {
  double mean = 0.0;
  for (std::size_t j : split.train) mean += signals.target[j];
  mean /= static_cast<double>(split.train.size());
  double sum = 0.0;
  for (std::size_t j : split.train) sum += (signals.target[j] - mean) * (signals.target[j] - mean);
  const double spread = std::sqrt(sum / static_cast<double>(split.train.size()));
  return spread > 0.0 ? spread : 1.0;
}

void set_bounds(ceres::Problem& problem, std::vector<double>& theta,
                const std::vector<ParamSpec>& specs, const std::vector<double>& scales) {
  const std::size_t p = specs.size();
  for (std::size_t i = 0; i < p; ++i) {
    if (specs[i].lower > -1e299) {
      problem.SetParameterLowerBound(theta.data(), static_cast<int>(i), specs[i].lower / scales[i]);
    }
    if (specs[i].upper < 1e299) {
      problem.SetParameterUpperBound(theta.data(), static_cast<int>(i), specs[i].upper / scales[i]);
    }
  }
}

ceres::Solver::Options solver_options_for(const FitOptions& options) {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.function_tolerance = options.tolerance;
  solver_options.parameter_tolerance = options.tolerance;
  return solver_options;
}

// A free parameter ends at a bound when it sits there and the cost's gradient pushes past it.
std::vector<BoundHit> bound_hits(const Eigen::VectorXd& gradient, double rss,
                                 const std::vector<double>& theta,
                                 const std::vector<ParamSpec>& specs,
                                 const std::vector<double>& scales) {
  std::vector<BoundHit> hits;
  const std::size_t p = specs.size();
  for (std::size_t i = 0; i < p; ++i) {
    if (specs[i].fixed) continue;
    const double value = theta[i] * scales[i];
    const auto near = [&](double bound) {
      return std::abs(value - bound) <= 1e-6 * std::max(std::abs(bound), scales[i]);
    };
    const double g = gradient(static_cast<Eigen::Index>(i));
    const double tolerance = 1e-6 * std::max(rss, 1e-12);
    if (specs[i].lower > -1e299 && near(specs[i].lower) && g > tolerance) {
      hits.push_back({i, specs[i].name, true, specs[i].lower, specs[i].below_means});
    } else if (specs[i].upper < 1e299 && near(specs[i].upper) && g < -tolerance) {
      hits.push_back({i, specs[i].name, false, specs[i].upper, ""});
    }
  }
  return hits;
}

// Standard errors from the Jacobian at the solution (fixed parameters have none), and the bounds
// the solution ends at.
void add_uncertainty(const ChannelCost& cost, const std::vector<double>& theta,
                     const std::vector<ParamSpec>& specs, const std::vector<double>& scales,
                     const std::vector<int>& constant, FitResult& result) {
  const std::size_t p = specs.size();
  const std::size_t m = static_cast<std::size_t>(cost.num_residuals());
  std::vector<double> residuals(m), jacobian(m * p);
  double* jac_ptr = jacobian.data();
  const double* param_ptr = theta.data();
  result.std_errors.assign(p, 0.0);
  if (cost.Evaluate(&param_ptr, residuals.data(), &jac_ptr) && m > p) {
    Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(
        jacobian.data(), static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(p));
    double rss = 0.0;
    for (double r : residuals) rss += r * r;
    const std::size_t free = p - constant.size();
    const double sigma2 = rss / static_cast<double>(std::max<std::size_t>(1, m - free));
    Eigen::MatrixXd free_j = J;
    for (int i : constant) free_j.col(i).setZero();
    const Eigen::VectorXd gradient =
        free_j.transpose() *
        Eigen::Map<const Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(m));
    result.bound_hits = bound_hits(gradient, rss, theta, specs, scales);
    const Eigen::MatrixXd jtj = free_j.transpose() * free_j;
    const Eigen::MatrixXd cov = sigma2 * jtj.completeOrthogonalDecomposition().pseudoInverse();
    for (std::size_t i = 0; i < p; ++i) {
      const double var = cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i));
      result.std_errors[i] = var > 0.0 ? std::sqrt(var) * scales[i] : 0.0;
    }
  }
}

}  // namespace

std::string BoundHit::message() const {
  std::ostringstream out;
  if (at_lower && !meaning.empty()) {
    out << "the data want " << meaning;
  } else {
    out << "the data want " << name << (at_lower ? " below " : " above ") << bound;
  }
  return out.str();
}

FitResult evaluate_channel(const ChannelModel& model, const ChannelSignals& signals,
                           const Split& split) {
  FitResult result;
  result.model = model;
  result.std_errors.assign(model.params.size(), 0.0);
  result.prediction = predict(model, signals);
  result.train_error = normalised_error(signals.target, result.prediction, split.train);
  result.heldout_error = normalised_error(signals.target, result.prediction, split.heldout);
  return result;
}

FitResult fit_channel(const ChannelModel& start, const ChannelSignals& signals, const Split& split,
                      const FitOptions& options) {
  const SignalScales sc = signal_scales(signals);
  const auto specs = start.specs(sc);
  const std::size_t p = specs.size();
  if (p == 0) return evaluate_channel(start, signals, split);
  std::vector<double> scales(p), theta(p);
  for (std::size_t i = 0; i < p; ++i) {
    scales[i] = specs[i].scale;
    theta[i] = std::clamp(start.params[i], specs[i].lower, specs[i].upper) / scales[i];
  }
  const double target_scale = target_spread(signals, split);
  const std::size_t stride = std::max<std::size_t>(1, options.stride);

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  auto* cost = new ChannelCost(start, signals, split, scales, stride, target_scale,
                               util::resolve_threads(options.threads));
  problem.AddResidualBlock(cost, nullptr, theta.data());
  std::vector<int> constant;
  for (std::size_t i = 0; i < p; ++i) {
    if (specs[i].fixed) constant.push_back(static_cast<int>(i));
  }
  if (constant.size() == p) return evaluate_channel(start, signals, split);
  if (!constant.empty()) {
    problem.SetManifold(theta.data(), new ceres::SubsetManifold(static_cast<int>(p), constant));
  }
  set_bounds(problem, theta, specs, scales);
  ceres::Solver::Options solver_options = solver_options_for(options);
  Heartbeat heartbeat(options.on_iteration);
  if (options.on_iteration) solver_options.callbacks.push_back(&heartbeat);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);

  FitResult result;
  result.model = start;
  for (std::size_t i = 0; i < p; ++i) result.model.params[i] = theta[i] * scales[i];
  result.cost = summary.final_cost;

  add_uncertainty(*cost, theta, specs, scales, constant, result);
  result.prediction = predict(result.model, signals);
  result.train_error = normalised_error(signals.target, result.prediction, split.train);
  result.heldout_error = normalised_error(signals.target, result.prediction, split.heldout);
  return result;
}

std::vector<WindowEstimate> windowed_estimate(const ChannelModel& model, std::size_t param_index,
                                              const ChannelSignals& signals, std::size_t windows) {
  if (param_index >= model.params.size() || windows == 0) {
    throw std::invalid_argument("windowed_estimate: no such parameter or no window");
  }
  ChannelModel one = model;
  one.fixed.assign(model.params.size(), true);
  one.fixed[param_index] = false;
  std::vector<WindowEstimate> out;
  const std::size_t n = signals.size(), width = n / windows;
  if (width < 10) throw std::invalid_argument("windowed_estimate: windows too short");
  for (std::size_t w = 0; w < windows; ++w) {
    Split split;
    split.size = n;
    for (std::size_t i = w * width; i < std::min(n, (w + 1) * width); ++i) split.train.push_back(i);
    split.heldout = split.train;
    const FitResult fit = fit_channel(one, signals, split);
    out.push_back({signals.time[split.train[split.train.size() / 2]], fit.model.params[param_index],
                   fit.std_errors[param_index]});
  }
  return out;
}

}  // namespace rths::identify
