#include "analysis/sweep/batch_kernel.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "util/parallel_for.h"

// The lane loops work on 8-double vectors (GCC vector extension), so vectorisation does not
// depend on the auto-vectoriser's mood; target_clones compiles them for AVX-512, AVX2 and baseline
// x86-64 and picks one at load time, so the binary runs on any x86-64. fp-contract=off keeps every
// clone from fusing multiply-adds: all clones (and core::simulate, built for baseline x86-64) then
// round alike, and a sweep sharded over different machines gives the same numbers. The peak uses a
// compare-select
// (`x > p ? x : p`) rather than std::fmax, |u| a sign-bit mask rather than std::fabs, and the
// divergence flag a compare, not a branch: NaN-aware library calls would not vectorise.
#define RTHS_KERNEL_CLONES \
  __attribute__((target_clones("avx512f", "avx2", "default"), optimize("fp-contract=off")))

// GCC notes (-Wpsabi) that returning a 64-byte vector changes the ABI between builds with and
// without AVX-512. These vectors never cross a function boundary that is not inlined in this
// file, and every clone is compiled here with the same flags, so no two ABIs ever meet.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace rths::analysis {
namespace {

struct KernelArgs {
  const double* ground;  // samples at t_{k+1}, ...
  std::size_t samples;
  int padded;
  double dt, half_dt, half_dt_squared;
  const double *mass, *effective_inverse, *damping, *k_numerical, *k_experimental;
  double *u, *v, *a, *peak;
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
constexpr int kVectorLanes = 8;

// Eight doubles as one value (GCC/Clang vector extension): the loop body below is written once
// and becomes one AVX-512 instruction, two AVX2 or four SSE2 ones per operation, whichever clone
// runs. State arrays and ring rows are 64-byte aligned.
typedef double Vec8 __attribute__((vector_size(64)));
typedef long long Mask8 __attribute__((vector_size(64)));

// kMode: 0 = no delay, 1 = shift with n >= 1 whole steps, 2 = shift with n = 0 (less than dt).
// Advances kVectors vectors (8 lanes each, from vector `first`) over every sample, with u, v, a
// and the peak held in registers for the whole record: only the ring is stored per step.
template <int kMode, int kVectors>
[[gnu::always_inline]] inline void advance_block(const KernelArgs& s, int first) {
  const Vec8 zero = {};
  const Vec8 dt = zero + s.dt, half_dt = zero + s.half_dt,
             half_dt_squared = zero + s.half_dt_squared;
  const Vec8 weight_new = zero + s.weight_new, weight_old = zero + s.weight_old;
  const Mask8 no_bits = {};
  const Mask8 magnitude_bits = no_bits + 0x7fffffffffffffffLL;
  const auto load = [first](const double* p, int j) {
    return *reinterpret_cast<const Vec8*>(p + (first + j) * kVectorLanes);
  };
  Vec8 u[kVectors], v[kVectors], a[kVectors], peak[kVectors];
  Vec8 mass[kVectors], effective_inverse[kVectors], damping[kVectors], kn[kVectors], ke[kVectors];
#pragma GCC unroll 8
  for (int j = 0; j < kVectors; ++j) {
    u[j] = load(s.u, j);
    v[j] = load(s.v, j);
    a[j] = load(s.a, j);
    peak[j] = load(s.peak, j);
    mass[j] = load(s.mass, j);
    effective_inverse[j] = load(s.effective_inverse, j);
    damping[j] = load(s.damping, j);
    kn[j] = load(s.k_numerical, j);
    ke[j] = load(s.k_experimental, j);
  }
  long k = s.step;
  for (std::size_t i = 0; i < s.samples; ++i, ++k) {
    const Vec8 ground = zero + s.ground[i];
    const std::size_t lane0 = static_cast<std::size_t>(first) * kVectorLanes;
    auto* __restrict written = reinterpret_cast<Vec8*>(
        s.ring + ((static_cast<std::size_t>(k + 1) & s.ring_mask) * kW) + lane0);
    const auto* __restrict newer = reinterpret_cast<const Vec8*>(
        s.ring + ((static_cast<std::size_t>(k + 1 - s.whole_steps) & s.ring_mask) * kW) + lane0);
    const auto* __restrict older = reinterpret_cast<const Vec8*>(
        s.ring + ((static_cast<std::size_t>(k - s.whole_steps) & s.ring_mask) * kW) + lane0);
#pragma GCC unroll 8
    for (int j = 0; j < kVectors; ++j) {
      const Vec8 u_next = u[j] + dt * v[j] + half_dt_squared * a[j];
      Vec8 realised = u_next;
      if constexpr (kMode == 1) {
        written[j] = u_next;
        realised = weight_old * older[j] + weight_new * newer[j];
      } else if constexpr (kMode == 2) {
        written[j] = u_next;
        realised = weight_old * older[j] + weight_new * u_next;
      }
      const Vec8 restoring = kn[j] * u_next + ke[j] * realised;
      const Vec8 load_next = -mass[j] * ground;
      const Vec8 rhs = (load_next - restoring) - damping[j] * (v[j] + half_dt * a[j]);
      const Vec8 a_next = effective_inverse[j] * rhs;
      v[j] = v[j] + half_dt * (a[j] + a_next);
      u[j] = u_next;
      a[j] = a_next;
      // |u| by clearing the sign bit, max by compare-select: a NaN never replaces the peak, and
      // a lane that diverges passes the bound (and keeps a peak above it) before any NaN.
      const Vec8 magnitude =
          reinterpret_cast<Vec8>(reinterpret_cast<Mask8>(u_next) & magnitude_bits);
      peak[j] = magnitude > peak[j] ? magnitude : peak[j];
    }
    if (s.history) {
      double* row = s.history + i * static_cast<std::size_t>(s.lanes);
      for (int j = 0; j < kVectors; ++j) {
        alignas(64) double lanes[kVectorLanes];
        *reinterpret_cast<Vec8*>(lanes) = u[j];
        const int lane = (first + j) * kVectorLanes;
        for (int l = 0; l < kVectorLanes && lane + l < s.lanes; ++l) row[lane + l] = lanes[l];
      }
    }
  }
#pragma GCC unroll 8
  for (int j = 0; j < kVectors; ++j) {
    *reinterpret_cast<Vec8*>(s.u + (first + j) * kVectorLanes) = u[j];
    *reinterpret_cast<Vec8*>(s.v + (first + j) * kVectorLanes) = v[j];
    *reinterpret_cast<Vec8*>(s.a + (first + j) * kVectorLanes) = a[j];
    *reinterpret_cast<Vec8*>(s.peak + (first + j) * kVectorLanes) = peak[j];
  }
}

// Splits the lanes into register blocks of at most four vectors (4 x 9 live vectors fit the 32
// AVX-512 registers), e.g. 7 vectors = 4 + 3.
template <int kMode>
[[gnu::always_inline]] inline void advance_lanes(KernelArgs& s) {
  const int vectors = s.padded / kVectorLanes;
  int first = 0;
  while (first < vectors) {
    const int remaining = vectors - first;
    const int blocks_left = (remaining + 3) / 4;
    const int count = (remaining + blocks_left - 1) / blocks_left;
    switch (count) {
      case 1: advance_block<kMode, 1>(s, first); break;
      case 2: advance_block<kMode, 2>(s, first); break;
      case 3: advance_block<kMode, 3>(s, first); break;
      default: advance_block<kMode, 4>(s, first); break;
    }
    first += count;
  }
  s.step += static_cast<long>(s.samples);
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
    ring_storage_.assign(rows * kMaxLanes + kLaneMultiple, 0.0);
    void* base = ring_storage_.data();
    std::size_t space = ring_storage_.size() * sizeof(double);
    ring_row0_ =
        static_cast<double*>(std::align(64, rows * kMaxLanes * sizeof(double), base, space));
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
  args.mass = mass_;
  args.effective_inverse = effective_inverse_;
  args.damping = damping_;
  args.k_numerical = k_numerical_;
  args.k_experimental = k_experimental_;
  args.u = u_;
  args.v = v_;
  args.a = a_;
  args.peak = peak_;
  args.ring = ring_row0_;
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
        ring_row0_[row * kMaxLanes + l] = u_[l] + dt_ * v_[l] + args.half_dt_squared * a_[l];
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
    // Diverged: |u| passed the bound at some step (the peak keeps it), or u ended as NaN.
    out[l].diverged = !(peak_[l] <= bound_) || std::isnan(u_[l]);
  }
  return out;
}

namespace {

// Splits n lanes into work items of whole 8-lane vectors, at most one register block (4 vectors)
// each, as even as possible: 100 lanes = 13 vectors = 4 + 3 + 3 + 3 (104 lanes computed). Small
// items keep every thread busy even when a core is shared with other processes.
std::vector<std::pair<std::size_t, std::size_t>> split_lanes(std::size_t lanes) {
  constexpr std::size_t kVectorsPerItem = 4;
  const std::size_t vectors = (lanes + kVectorLanes - 1) / kVectorLanes;
  const std::size_t items = (vectors + kVectorsPerItem - 1) / kVectorsPerItem;
  std::vector<std::pair<std::size_t, std::size_t>> out;  // (first lane, count)
  std::size_t first_vector = 0;
  for (std::size_t i = 0; i < items; ++i) {
    const std::size_t count = (vectors - first_vector + (items - i) - 1) / (items - i);
    const std::size_t first = first_vector * kVectorLanes;
    out.emplace_back(first, std::min(count * kVectorLanes, lanes - first));
    first_vector += count;
  }
  return out;
}

}  // namespace

std::vector<LaneOutcome> run_linear_sdof_lanes(std::span<const SdofLane> lanes,
                                               std::span<const double> ground_acceleration,
                                               double dt, double delay,
                                               const BatchRunOptions& options,
                                               std::vector<std::vector<double>>* histories) {
  std::vector<LaneOutcome> outcomes(lanes.size());
  if (histories) histories->assign(lanes.size(), {});
  if (lanes.empty()) return outcomes;
  if (ground_acceleration.empty()) throw std::invalid_argument("batch run: the motion is empty");
  const auto items = split_lanes(lanes.size());
  util::parallel_for(items.size(), options.threads, [&](std::size_t item) {
    const auto [first, count] = items[item];
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

std::vector<std::vector<LaneOutcome>> run_linear_sdof_grid(
    std::span<const SdofLane> lanes, std::span<const double> delays,
    std::span<const double> ground_acceleration, double dt, const BatchRunOptions& options) {
  std::vector<std::vector<LaneOutcome>> outcomes(delays.size(),
                                                 std::vector<LaneOutcome>(lanes.size()));
  if (lanes.empty() || delays.empty()) return outcomes;
  if (ground_acceleration.empty()) throw std::invalid_argument("batch run: the motion is empty");
  const auto items = split_lanes(lanes.size());
  util::parallel_for(items.size() * delays.size(), options.threads, [&](std::size_t item) {
    const std::size_t d = item / items.size();
    const auto [first, count] = items[item % items.size()];
    LinearSdofBatch batch(lanes.subspan(first, count), dt, delays[d], options.divergence_bound);
    batch.start(ground_acceleration[0]);
    batch.advance(ground_acceleration.subspan(1), nullptr);
    const auto result = batch.outcomes();
    std::copy(result.begin(), result.end(),
              outcomes[d].begin() + static_cast<std::ptrdiff_t>(first));
  });
  return outcomes;
}

}  // namespace rths::analysis
