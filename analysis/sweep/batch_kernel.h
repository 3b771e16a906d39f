#pragma once
// Batch kernel: many linear SDOF hybrid systems under one ground motion, advanced together in
// SIMD lanes. It is the fast path of `rths sweep` for the cases it covers and must agree with
// core::simulate to round-off for them: explicit Newmark (beta = 0, gamma = 1/2), SDOF, linear
// springs, and no delay or a constant time shift.
//
// Per lane (mass m kg, damping c N s/m, numerical stiffness k_n N/m, experimental k_e N/m), with
// p_k = -m a_g[k] (a_g in m/s^2) and every lane sharing dt (s) and the delay tau (s):
//   u+   = u + dt v + dt^2/2 a                                  (command sent to the actuator)
//   u_r  = u+(t - tau), linear interpolation on the command history; before t = tau + dt the
//          first command u_1 is held (exactly as core::TimeShift, whose first push is at t_1)
//   a+   = (p+ - (k_n u+ + k_e u_r) - c (v + dt/2 a)) / (m + dt/2 c)
//   v+   = v + dt/2 (a + a+)
// Initial state: rest, a_0 = p_0 / m. Row k of a history is t_k = k dt, k = 0..N-1 for N
// motion samples (row 0 is the initial rest state), like core::SimulationResult.
//
// Outputs per lane: peak |u| over the record, whether |u| ever left the divergence bound (or
// became NaN), and optionally the whole displacement history. The benchmark path keeps no
// history, so memory does not grow with the record or the grid.
//
// Lanes are independent: a lane's result does not depend on which other lanes share its batch,
// so a grid split into any batches (or shards) gives the same numbers bit for bit.

#include <cstddef>
#include <span>
#include <vector>

namespace rths::analysis {

struct SdofLane {
  double mass = 1.0;                    // kg
  double damping = 0.0;                 // N s/m
  double stiffness_numerical = 0.0;     // N/m, (1 - alpha) k: sees u+ directly
  double stiffness_experimental = 0.0;  // N/m, alpha k: sees the delayed u_r
};

struct LaneOutcome {
  double peak_abs = 0.0;  // m, max |u_k| over the record (meaningless once diverged)
  bool diverged = false;  // |u| exceeded the bound, or became NaN
};

// Up to kMaxLanes lanes sharing dt, the motion and one time-shift delay. The class holds the
// whole state (u, v, a, peaks, the command ring) so a record can be fed in pieces.
class LinearSdofBatch {
 public:
  static constexpr int kMaxLanes = 64;
  static constexpr int kLaneMultiple = 8;  // lanes are padded to whole AVX-512 vectors

  // @pre 1 <= lanes.size() <= kMaxLanes, dt > 0, delay >= 0, every mass > 0.
  // Throws std::invalid_argument otherwise.
  LinearSdofBatch(std::span<const SdofLane> lanes, double dt, double delay,
                  double divergence_bound = 1.0e3);

  // Sets the rest state under the first ground-acceleration sample a_g[0] (m/s^2).
  void start(double first_ground_acceleration);
  // Advances one step per sample (the samples at t_{k+1}, t_{k+2}, ...). When `history` is not
  // null it receives u for each of those steps, row-major: history[i * lanes() + lane].
  // Real-time safe: no allocation.
  void advance(std::span<const double> next_ground_acceleration, double* history);

  int lanes() const { return lanes_; }
  std::vector<LaneOutcome> outcomes() const;

 private:
  int lanes_ = 0, padded_ = 0;
  double dt_, delay_, bound_;
  long whole_steps_ = 0;   // n = floor(tau / dt) (snapped when tau is a whole multiple)
  double fraction_ = 0.0;  // f = tau / dt - n, in [0, 1)
  long step_ = 0;          // index k of the last computed state
  std::size_t ring_mask_ = 0;
  alignas(64) double mass_[kMaxLanes], effective_inverse_[kMaxLanes], damping_[kMaxLanes],
      k_numerical_[kMaxLanes], k_experimental_[kMaxLanes];
  alignas(64) double u_[kMaxLanes], v_[kMaxLanes], a_[kMaxLanes], peak_[kMaxLanes];
  // (ring_mask_ + 1) rows of kMaxLanes commands, u_k in row k & mask, starting at ring_row0_ (the
  // first 64-byte aligned element of ring_storage_).
  std::vector<double> ring_storage_;
  double* ring_row0_ = nullptr;
};

struct BatchRunOptions {
  double divergence_bound = 1.0e3;  // m
  int threads = 1;                  // worker threads over the lane batches
};

// Runs every lane over the whole motion (sampled at dt) with the time-shift delay `delay` (0 =
// none), splitting the lanes into balanced batches of at most kMaxLanes. When `histories` is not
// null it is resized to lanes.size() vectors of motion.size() displacements.
std::vector<LaneOutcome> run_linear_sdof_lanes(
    std::span<const SdofLane> lanes, std::span<const double> ground_acceleration, double dt,
    double delay, const BatchRunOptions& options = {},
    std::vector<std::vector<double>>* histories = nullptr);

// The same lanes under several delays: outcomes[d][lane] for delays[d]. Every (delay, batch) pair
// is one work item, so all threads stay busy without storing any history.
std::vector<std::vector<LaneOutcome>> run_linear_sdof_grid(
    std::span<const SdofLane> lanes, std::span<const double> delays,
    std::span<const double> ground_acceleration, double dt, const BatchRunOptions& options = {});

}  // namespace rths::analysis
