#include "analysis/batch_kernel.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

#include "analysis/parallel_for.h"

// The lane loops are written as plain loops over arrays of a fixed maximum width, which GCC
// vectorises; target_clones compiles them for AVX-512, AVX2 and baseline x86-64 and picks one at
// load time, so the binary runs on any x86-64. fp-contract=off keeps every clone from fusing
// multiply-adds: all clones (and core::simulate, built for baseline x86-64) then round alike, and
// a sweep sharded over different machines gives the same numbers. The peak uses a compare-select
// (`x > p ? x : p`) rather than std::fmax and the divergence flag a compare, not a branch: both
// vectorise, where NaN-aware library calls would not.
#define RTHS_KERNEL_CLONES \
  __attribute__((target_clones("avx512f", "avx2", "default"), optimize("fp-contract=off")))

namespace rths::analysis {
namespace {

struct KernelArgs {
  const double* ground;  // samples at t_{k+1}, ...
  std::size_t samples;
  int padded;
  double dt, half_dt, half_dt_squared, bound;
  const double *mass, *effective_inverse, *damping, *k_numerical, *k_experimental;
  double *u, *v, *a, *peak, *bad;
  // Time shift: u_r = w_old u[k+1-n-1] + w_new u[k+1-n]; for n = 0 the newer one is u+.
  double* ring;
  std::size_t ring_mask;
  long whole_steps;
  double weight_new, weight_old;
  long step;  // index of the state held in u, v, a
  double* history;
  int lanes;
};

constexpr int kW = LinearSdofBatch::kMaxLanes;

// kMode: 0 = no delay, 1 = shift with n >= 1 whole steps, 2 = shift with n = 0 (less than dt).
template <int kMode>
[[gnu::always_inline]] inline void advance_lanes(KernelArgs& s) {
  const int padded = s.padded;
  const double dt = s.dt, half_dt = s.half_dt, half_dt_squared = s.half_dt_squared;
  const double bound = s.bound, weight_new = s.weight_new, weight_old = s.weight_old;
  const double* __restrict mass = s.mass;
  const double* __restrict effective_inverse = s.effective_inverse;
  const double* __restrict damping = s.damping;
  const double* __restrict k_numerical = s.k_numerical;
  const double* __restrict k_experimental = s.k_experimental;
  double* __restrict u = s.u;
  double* __restrict v = s.v;
  double* __restrict a = s.a;
  double* __restrict peak = s.peak;
  double* __restrict bad = s.bad;
  long k = s.step;
  for (std::size_t i = 0; i < s.samples; ++i, ++k) {
    const double ground = s.ground[i];
    double* __restrict written = s.ring + ((static_cast<std::size_t>(k + 1) & s.ring_mask) * kW);
    const double* __restrict newer =
        s.ring + ((static_cast<std::size_t>(k + 1 - s.whole_steps) & s.ring_mask) * kW);
    const double* __restrict older =
        s.ring + ((static_cast<std::size_t>(k - s.whole_steps) & s.ring_mask) * kW);
    for (int l = 0; l < padded; ++l) {
      const double u_next = u[l] + dt * v[l] + half_dt_squared * a[l];
      double realised = u_next;
      if constexpr (kMode == 1) {
        written[l] = u_next;
        realised = weight_old * older[l] + weight_new * newer[l];
      } else if constexpr (kMode == 2) {
        written[l] = u_next;
        realised = weight_old * older[l] + weight_new * u_next;
      }
      const double restoring = k_numerical[l] * u_next + k_experimental[l] * realised;
      const double load = -mass[l] * ground;
      const double rhs = (load - restoring) - damping[l] * (v[l] + half_dt * a[l]);
      const double a_next = effective_inverse[l] * rhs;
      v[l] = v[l] + half_dt * (a[l] + a_next);
      u[l] = u_next;
      a[l] = a_next;
      const double magnitude = std::fabs(u_next);
      peak[l] = magnitude > peak[l] ? magnitude : peak[l];
      bad[l] = magnitude <= bound ? bad[l] : 1.0;  // NaN compares false: flagged too
    }
    if (s.history) {
      double* row = s.history + i * static_cast<std::size_t>(s.lanes);
      for (int l = 0; l < s.lanes; ++l) row[l] = u[l];
    }
  }
  s.step = k;
}

RTHS_KERNEL_CLONES void advance_undelayed(KernelArgs& s) { advance_lanes<0>(s); }
RTHS_KERNEL_CLONES void advance_shifted(KernelArgs& s) { advance_lanes<1>(s); }
RTHS_KERNEL_CLONES void advance_shifted_within_step(KernelArgs& s) { advance_lanes<2>(s); }

}  // namespace

LinearSdofBatch::LinearSdofBatch(std::span<const SdofLane> lanes, double dt, double delay,
                                 double divergence_bound)
    : dt_(dt), delay_(delay), bound_(divergence_bound) {
  if (lanes.empty() || lanes.size() > static_cast<std::size_t>(kMaxLanes)) {
    throw std::invalid_argument("LinearSdofBatch: needs 1.." + std::to_string(kMaxLanes) +
                                " lanes, got " + std::to_string(lanes.size()));
  }
  if (!(dt > 0) || !std::isfinite(dt)) {
    throw std::invalid_argument("LinearSdofBatch: dt must be > 0 s, got " + std::to_string(dt));
  }
  if (!(delay >= 0) || !std::isfinite(delay)) {
    throw std::invalid_argument("LinearSdofBatch: delay must be >= 0 s, got " +
                                std::to_string(delay));
  }
  lanes_ = static_cast<int>(lanes.size());
  padded_ = (lanes_ + kLaneMultiple - 1) / kLaneMultiple * kLaneMultiple;
  for (int l = 0; l < kMaxLanes; ++l) {
    // Padding lanes copy lane 0 so they stay finite and never slow the loop with denormals.
    const SdofLane& lane = lanes[l < lanes_ ? l : 0];
    if (!(lane.mass > 0)) {
      throw std::invalid_argument("LinearSdofBatch: lane " + std::to_string(l) +
                                  " mass must be > 0 kg");
    }
    mass_[l] = lane.mass;
    damping_[l] = lane.damping;
    // As core::ExplicitNewmark: the inverse of (m + dt/2 c), then multiplied.
    effective_inverse_[l] = 1.0 / (lane.mass + 0.5 * dt * lane.damping);
    k_numerical_[l] = lane.stiffness_numerical;
    k_experimental_[l] = lane.stiffness_experimental;
  }
  const double steps = delay / dt;
  double whole = std::floor(steps);
  // A delay meant as a whole number of steps (14 ms at 1 ms) is not one in binary; snap it so
  // the interpolation weight is exactly 0 rather than 1e-13 off.
  if (std::abs(steps - std::round(steps)) <= 1e-9 * std::max(1.0, steps)) whole = std::round(steps);
  if (whole > 1e7) throw std::invalid_argument("LinearSdofBatch: delay / dt exceeds 1e7 steps");
  whole_steps_ = static_cast<long>(whole);
  fraction_ = std::max(0.0, steps - whole);
  if (delay > 0) {
    const std::size_t rows = std::bit_ceil(static_cast<std::size_t>(whole_steps_) + 2);
    ring_mask_ = rows - 1;
    ring_.assign(rows * kMaxLanes, 0.0);
  }
  start(0.0);
}

void LinearSdofBatch::start(double first_ground_acceleration) {
  for (int l = 0; l < kMaxLanes; ++l) {
    u_[l] = 0.0;
    v_[l] = 0.0;
    // core: a0 = M^-1 (p0 - C v0 - r0) with p0 = -M iota a_g[0].
    const double load = -mass_[l] * first_ground_acceleration;
    a_[l] = (1.0 / mass_[l]) * ((load - damping_[l] * 0.0) - 0.0);
    peak_[l] = 0.0;
    bad_[l] = 0.0;
  }
  step_ = 0;
}

void LinearSdofBatch::advance(std::span<const double> next_ground_acceleration, double* history) {
  if (next_ground_acceleration.empty()) return;
  KernelArgs args{};
  args.ground = next_ground_acceleration.data();
  args.samples = next_ground_acceleration.size();
  args.padded = padded_;
  args.dt = dt_;
  args.half_dt = 0.5 * dt_;
  args.half_dt_squared = 0.5 * dt_ * dt_;
  args.bound = bound_;
  args.mass = mass_;
  args.effective_inverse = effective_inverse_;
  args.damping = damping_;
  args.k_numerical = k_numerical_;
  args.k_experimental = k_experimental_;
  args.u = u_;
  args.v = v_;
  args.a = a_;
  args.peak = peak_;
  args.bad = bad_;
  args.ring = ring_.data();
  args.ring_mask = ring_mask_;
  args.whole_steps = whole_steps_;
  args.weight_new = 1.0 - fraction_;
  args.weight_old = fraction_;
  args.step = step_;
  args.history = history;
  args.lanes = lanes_;
  if (delay_ > 0 && step_ == 0) {
    // core::TimeShift holds its first command, u_1, for every query before t_1: fill the ring
    // with u_1 (computed exactly as the loop will) so every look-back before t_1 reads it.
    for (std::size_t row = 0; row <= ring_mask_; ++row) {
      for (int l = 0; l < kMaxLanes; ++l) {
        ring_[row * kMaxLanes + l] = u_[l] + dt_ * v_[l] + args.half_dt_squared * a_[l];
      }
    }
  }
  if (delay_ <= 0) {
    advance_undelayed(args);
  } else if (whole_steps_ >= 1) {
    advance_shifted(args);
  } else {
    advance_shifted_within_step(args);
  }
  step_ = args.step;
}

std::vector<LaneOutcome> LinearSdofBatch::outcomes() const {
  std::vector<LaneOutcome> out(static_cast<std::size_t>(lanes_));
  for (int l = 0; l < lanes_; ++l) {
    out[l].peak_abs = peak_[l];
    out[l].diverged = bad_[l] != 0.0;
  }
  return out;
}

std::vector<LaneOutcome> run_linear_sdof_lanes(std::span<const SdofLane> lanes,
                                               std::span<const double> ground_acceleration,
                                               double dt, double delay,
                                               const BatchRunOptions& options,
                                               std::vector<std::vector<double>>* histories) {
  std::vector<LaneOutcome> outcomes(lanes.size());
  if (histories) histories->assign(lanes.size(), {});
  if (lanes.empty()) return outcomes;
  if (ground_acceleration.empty()) throw std::invalid_argument("batch run: the motion is empty");
  // Balanced batches: 100 lanes become 2 x 50 (padded to 56), not 64 + 36.
  const std::size_t batches = (lanes.size() + static_cast<std::size_t>(LinearSdofBatch::kMaxLanes) - 1) / static_cast<std::size_t>(LinearSdofBatch::kMaxLanes);
  const std::size_t per_batch = (lanes.size() + batches - 1) / batches;
  parallel_for(batches, options.threads, [&](std::size_t b) {
    const std::size_t first = b * per_batch;
    const std::size_t count = std::min(per_batch, lanes.size() - first);
    LinearSdofBatch batch(lanes.subspan(first, count), dt, delay, options.divergence_bound);
    batch.start(ground_acceleration[0]);
    const auto rest = ground_acceleration.subspan(1);
    if (histories) {
      std::vector<double> block(rest.size() * count);
      batch.advance(rest, block.data());
      for (std::size_t l = 0; l < count; ++l) {
        std::vector<double>& h = (*histories)[first + l];
        h.resize(ground_acceleration.size());
        h[0] = 0.0;
        for (std::size_t i = 0; i < rest.size(); ++i) h[i + 1] = block[i * count + l];
      }
    } else {
      batch.advance(rest, nullptr);
    }
    const auto result = batch.outcomes();
    std::copy(result.begin(), result.end(), outcomes.begin() + static_cast<std::ptrdiff_t>(first));
  });
  return outcomes;
}

}  // namespace rths::analysis
