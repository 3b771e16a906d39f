#pragma once
// Records written by a closed-loop simulation of the paper frame that shares no model with rths's
// nodes, for the identification tests: its own integrator (explicit Newmark), its own actuator
// (a 14 ms shift, then whatever the rig adds), its own specimen and its own sensors with noise and
// 16-bit converters. The record holds the declared study (the paper frame, linear specimen, a
// 14 ms shift), whatever the rig truly did: as a lab's record made by another controller would.
//
// Paper frame: m = 1000 kg, T = 0.5 s, 5 % modal damping, the experimental part a third of the
// storey stiffness (k_e = 52,638 N/m), dt = 1 ms, the 1979 Imperial Valley record (the motion is
// read by rths, since it is an input, not a model). Per step k (Newmark, gamma = 1/2, beta = 0):
//   u_k = u + dt v + dt^2/2 a; command x_c = u_k; the actuator: x = x_c(t - 14 ms) -> first order
//   (tau) -> backlash (width) -> velocity limit (v_max) -> stroke (the rod's ends at +-s) -> gain;
//   -> x - c x^3 (a valve's flow gain); specimen: f = k_e s (1 - softening t / duration) x
//   (linear; x compression_stiffness where x < 0) or Bouc-Wen (alpha, uy, n = 1, beta = gamma) on
//   x, + c_s (x - x_prev) / dt + a pump's ripple F_r sin(2 pi f_r t); sensors: x_m = AD(g_x x + x0 + n_x), f_m = AD(g_f f + f0 + f1 t +
//   n_f), AD a 16-bit converter over +-range; then a_k = (p_k - c (v + dt/2 a) - k_n u_k - f_m) /
//   (m + dt/2 c), v += dt/2 (a + a_k).

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "runtime/node/schema.h"
#include "runtime/record/record.h"
#include "study/study.h"
#include "study/study_inputs.h"
#include "tests/runtime/test_support.h"

namespace rths::test {

// What the platform did (0 = nothing): a real-time loop that went on with an older answer at
// some steps. The answer used at step k was the one to step k - age_k: age 1 on a random
// `late_share` of the steps (a link as slow as the step), and `burst_age` over `burst_steps`
// steps every `burst_every` s (a stall: those steps overran). The node still answered every
// command in turn, but `lost_steps` answers in a row every `lost_every` s never arrived (the
// network lost them): the loop went on with the last answer it had. The record then says real
// time, with node 1 an actuator emulator.
struct PlatformTruth {
  double late_share = 0.0;
  int burst_steps = 0, burst_age = 0;
  double burst_every = 0.0;  // s
  int lost_steps = 0;
  double lost_every = 0.0;  // s
  bool any() const {
    return late_share > 0.0 || (burst_steps > 0 && burst_age > 0) || lost_steps > 0;
  }
};

// What the network did on node 1's link (0 = nothing), in a record whose loop waited for every
// answer (lockstep, so the lag reaches no response): a round trip of 0.4 ms that drifts linearly
// by `drift` over the run, with a spike of `spike_height` over `spike_steps` steps every
// `spike_every` s (a host's periodic task) and a Gaussian jitter, and the node's
// clock `clock_offset` ahead of the coordinator's (the one-way stamps carry it).
struct NetworkTruth {
  double drift = 0.0;         // s, over the run
  double spike_height = 0.0;  // s
  double spike_every = 0.0;   // s
  int spike_steps = 1;
  double jitter = 0.0;        // s, standard deviation
  double clock_offset = 0.0;  // s, node clock - coordinator clock
  bool any() const { return drift != 0.0 || spike_height > 0.0 || clock_offset != 0.0; }
};

// What the rig truly does beyond the declared 14 ms shift (0 = absent).
struct RigTruth {
  double time_constant = 0.0;        // s, an extra first-order lag
  double gain = 1.0;                 // of the actuator
  double backlash = 0.0;             // m, total width
  double max_velocity = 0.0;         // m/s
  double stroke = 0.0;               // m, either side of the centre
  double stiffness_scale = 1.0;      // of the specimen's (linear or initial) stiffness
  bool bouc_wen = false;             // a hysteretic specimen: alpha 0.1, uy 4 mm
  double specimen_damping = 0.0;     // N s/m, a viscous force on the specimen's drift rate
  double squared_damping = 0.0;      // N s^2/m^2, a force c v |v| on the drift rate v
  double displacement_scale = 1.0;   // of the displacement sensor (g_x)
  double displacement_offset = 0.0;  // m, on the displacement sensor
  double force_scale = 1.0;          // of the load cell (g_f)
  double force_offset = 0.0;         // N, on the load cell
  double force_drift = 0.0;          // N/s
  // Effects identify has no stage for (unexplained.h describes them):
  double force_ripple = 0.0;           // N, a pump's ripple on the specimen's force
  double ripple_frequency = 0.0;       // Hz
  double compression_stiffness = 1.0;  // x the stiffness where the drift is negative
  double softening = 0.0;              // the stiffness's fall over the run, a share of it
  double actuator_cubic = 0.0;         // 1/m^2: the stroke x - c x^3 (a valve's flow gain)
  double displacement_noise = 2e-6;    // m RMS
  double force_noise = 0.5;            // N RMS
  double displacement_range = 0.2;     // m, 16-bit converter
  double force_range = 20000.0;        // N
  // A rattle on the load cell for a moment: rattle_force N at rattle_frequency Hz over
  // [rattle_start, rattle_end) s (an event: no stage and no description holds it).
  double rattle_force = 0.0, rattle_frequency = 0.0, rattle_start = 0.0, rattle_end = 0.0;
  // Events on the load cell's reading: it holds its value over [hold_start, hold_end) s; a spike
  // of spike_force N on the one sample at each of spike_times s; its offset steps by step_force N
  // at step_time s and stays.
  double hold_start = 0.0, hold_end = 0.0;
  double spike_force = 0.0;
  std::vector<double> spike_times;
  double step_force = 0.0, step_time = 0.0;
  // A specimen that loses capacity_drop of its stiffness at drop_time s, for the rest of the run.
  double capacity_drop = 0.0, drop_time = 0.0;
  // m over the record, linear in time: the displacement sensor's mount creeps and the loop
  // follows the reading, so the specimen travels the reading less the creep (a bracket that
  // creeps); the reading itself stays true to the command.
  double followed_creep = 0.0;
  std::uint64_t seed = 7;
  PlatformTruth platform;
  NetworkTruth network;  // in a lockstep record: give no platform beside it
};

inline double rattle(const RigTruth& rig, double t) {
  if (t < rig.rattle_start || t >= rig.rattle_end) return 0.0;
  return rig.rattle_force * std::sin(2.0 * std::numbers::pi * rig.rattle_frequency * t);
}

// What the load cell's reading adds at step k (t = k dt): a spike, an offset's step.
inline double reading_events(const RigTruth& rig, double t, double dt) {
  double out = t >= rig.step_time ? rig.step_force : 0.0;
  for (double at : rig.spike_times)
    if (std::abs(t - at) < 0.5 * dt) out += rig.spike_force;
  return out;
}

inline double converted(double x, double range) {
  const double quantum = range / 32768.0;
  return std::round(std::clamp(x, -range, range) / quantum) * quantum;
}

// The actuator's displacement from the delayed command, with the rig's own effects.
class TrueActuator {
 public:
  TrueActuator(const RigTruth& rig, double dt) : rig_(rig), dt_(dt) {}
  double step(double delayed_command) {
    double x = delayed_command;
    if (rig_.time_constant > 0.0) {
      const double e = std::exp(-dt_ / rig_.time_constant);
      x = lag_ = e * lag_ + (1.0 - e) * x;
    }
    if (rig_.backlash > 0.0)
      x = play_ = std::clamp(play_, x - 0.5 * rig_.backlash, x + 0.5 * rig_.backlash);
    if (rig_.max_velocity > 0.0)
      x = valve_ += std::clamp(x - valve_, -rig_.max_velocity * dt_, rig_.max_velocity * dt_);
    if (rig_.stroke > 0.0) x = std::clamp(x, -rig_.stroke, rig_.stroke);
    return rig_.gain * (x - rig_.actuator_cubic * x * x * x);
  }

 private:
  RigTruth rig_;
  double dt_, lag_ = 0.0, play_ = 0.0, valve_ = 0.0;
};

// The specimen's force (N) at displacement x (m): linear, or Bouc-Wen integrated with RK4.
class TrueSpecimen {
 public:
  TrueSpecimen(const RigTruth& rig, double k0, double duration)
      : rig_(rig), k0_(k0 * rig.stiffness_scale), duration_(duration) {}
  // At displacement x (m) at time t (s) after `dt` s: the spring (or hysteresis) plus the
  // viscous forces and the pump's ripple.
  double force(double x, double t, double dt) {
    const double rate = (x - last_) / dt;
    const double viscous =
        rig_.specimen_damping * rate + rig_.squared_damping * rate * std::abs(rate);
    const double ripple =
        rig_.force_ripple * std::sin(2.0 * std::numbers::pi * rig_.ripple_frequency * t);
    return viscous + spring(x, t) + ripple;
  }

 private:
  double spring(double x, double t) {
    if (!rig_.bouc_wen) {
      last_ = x;
      const double k = k0_ * (1.0 - rig_.softening * t / duration_) *
                       (x < 0.0 ? rig_.compression_stiffness : 1.0) *
                       (t >= rig_.drop_time ? 1.0 - rig_.capacity_drop : 1.0);
      return k * x;
    }
    const double du = x - last_, uy = 0.004, alpha = 0.1;
    const auto rate = [&](double z) {
      const double s = du * z > 0.0 ? 1.0 : (du * z < 0.0 ? -1.0 : 0.0);
      return 1.0 - std::abs(z) / uy * (0.5 * s + 0.5);
    };
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(du) / (uy / 100.0))));
    const double h = du / n;
    for (int i = 0; i < n; ++i) {
      const double k1 = rate(z_), k2 = rate(z_ + 0.5 * h * k1), k3 = rate(z_ + 0.5 * h * k2),
                   k4 = rate(z_ + h * k3);
      z_ += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    last_ = x;
    return alpha * k0_ * x + (1.0 - alpha) * k0_ * z_;
  }

  RigTruth rig_;
  double k0_, duration_, last_ = 0.0, z_ = 0.0;
};

// The declared study: the paper frame with its 14 ms shift, as the record's header holds it; a
// record of a platform that was late declares a real-time run with node 1 its actuator emulator
// (the numerical storey in the coordinator), one of a network a lockstep run with that node.
enum class RecordClock { kNone, kLockstep, kRealTime };
inline std::string independent_declared_study(double duration, RecordClock clock) {
  switch (clock) {
    case RecordClock::kNone: return paper_frame_study(duration, "");
    case RecordClock::kLockstep:
      return paper_frame_study(duration,
                               "deployment { clock: LOCKSTEP nodes { id: 1 kind: "
                               "ACTUATOR_EMULATOR } }");
    case RecordClock::kRealTime:
      return paper_frame_study(duration,
                               "deployment { clock: REAL_TIME max_overrun_fraction: -1 "
                               "max_missed_answers: 40 command_watchdog_periods: 40 "
                               "min_answer_fraction: -1 nodes { id: 1 kind: ACTUATOR_EMULATOR } }");
  }
  return {};
}

// The step whose answer the loop used at each step (PlatformTruth), and whether the step overran.
struct AnswerUsed {
  std::int64_t step = 0;
  bool overrun = false;
  std::uint64_t answers = 0;  // the answers that arrived up to the one used
};

// Whether step k's answer is one the network lost (PlatformTruth lost_steps, lost_every).
inline bool lost_answer(const PlatformTruth& platform, std::size_t k, double dt) {
  const auto period = static_cast<std::size_t>(std::llround(platform.lost_every / dt));
  return period > 0 && (k % period) >= period / 2 &&
         (k % period) < period / 2 + static_cast<std::size_t>(platform.lost_steps);
}

inline std::vector<AnswerUsed> answers_used(const PlatformTruth& platform, std::size_t steps,
                                            double dt, std::uint64_t seed) {
  std::vector<AnswerUsed> out(steps);
  std::mt19937_64 rng(seed ^ 0x5eedULL);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto period = static_cast<std::size_t>(std::llround(platform.burst_every / dt));
  for (std::size_t k = 0; k < steps; ++k) {
    int age = uniform(rng) < platform.late_share ? 1 : 0;
    const bool burst = period > 0 && k > period / 2 &&
                       (k % period) < static_cast<std::size_t>(platform.burst_steps);
    if (burst) age = std::max(age, platform.burst_age);
    // An answer the loop already moved past is not taken again: never older than the last one;
    // a lost one is never taken.
    std::int64_t used =
        std::max<std::int64_t>(k > 0 ? out[k - 1].step : 0, static_cast<std::int64_t>(k) - age);
    if (k > 0 && lost_answer(platform, static_cast<std::size_t>(used), dt)) used = out[k - 1].step;
    out[k] = {k == 0 ? 0 : used, burst, 0};
  }
  // The answers that arrived up to each step's used one: those to steps 1 .. used not lost.
  std::uint64_t count = 0;
  std::int64_t counted = 1;
  for (auto& u : out) {
    for (; counted <= u.step; ++counted)
      if (!lost_answer(platform, static_cast<std::size_t>(counted), dt)) ++count;
    u.answers = count;
  }
  return out;
}

// The network's lag at time t (s, on a 1 ms step) of a run of `duration` s (NetworkTruth), beyond
// its 0.4 ms.
inline double network_lag(const NetworkTruth& network, double t, double duration) {
  double lag = network.drift * t / duration;
  if (network.spike_every > 0.0) {
    const auto period = static_cast<std::int64_t>(std::llround(network.spike_every * 1000.0));
    const std::int64_t phase = static_cast<std::int64_t>(std::llround(t * 1000.0)) % period;
    if (phase >= period / 2 && phase < period / 2 + network.spike_steps)
      lag += network.spike_height;
  }
  return lag;
}

inline void add_link_sample(const AnswerUsed& used, std::size_t step, double dt,
                            const NetworkTruth& network, double duration, std::mt19937_64& rng,
                            runtime::StepRecord& r) {
  std::normal_distribution<double> jitter(0.0, 1.0);
  runtime::LinkSample& link = *r.add_links();
  const double age = static_cast<double>(static_cast<std::int64_t>(step) - used.step);
  const double t = static_cast<double>(step) * dt;
  link.set_node_id(1);
  link.set_answered_step(used.step);
  link.set_answers(used.answers);
  link.set_round_trip(0.0004 + age * dt + network_lag(network, t, duration) +
                      std::abs(network.jitter * jitter(rng)));
  link.set_one_way_down(0.5 * link.round_trip() + network.clock_offset);
  link.set_one_way_up(0.5 * link.round_trip() - network.clock_offset);
  r.set_overrun(used.overrun);
  r.set_lateness(used.overrun ? 0.002 : -0.0005);
}

// Writes the record of a `duration` s run of the rig `rig` under the declared study; returns its
// path.
inline std::filesystem::path independent_record(const std::string& name, const RigTruth& rig,
                                                double duration = 20.0) {
  const bool real_time = rig.platform.any(), linked = real_time || rig.network.any();
  const study::PreparedStudy declared = prepare(independent_declared_study(
      duration,
      real_time ? RecordClock::kRealTime : (linked ? RecordClock::kLockstep : RecordClock::kNone)));
  const double dt = 0.001, m = 1000.0, omega = 2.0 * std::numbers::pi / 0.5;
  const double k = m * omega * omega, c = 2.0 * 0.05 * m * omega;
  const double k_e = k / 3.0, k_n = k - k_e;
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_independent_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / (name + ".rthsrec");
  runtime::RecordWriter writer(path);
  runtime::RecordEntry entry;
  runtime::RunHeader& header = *entry.mutable_header();
  header.set_schema_version(runtime::kSchemaVersion);
  header.set_run_id(name);
  *header.mutable_study() = declared.config;
  header.set_case_name("lag_shift_14ms");
  header.set_clock(real_time ? "real_time" : "lockstep");
  if (linked) header.add_link_node_ids(1);
  header.set_dt(dt);
  header.set_dofs(1);
  header.set_actuators(1);
  writer.write(entry);
  entry.Clear();
  *entry.mutable_inputs()->mutable_study() = study::with_embedded_inputs(declared);
  writer.write(entry);

  const std::vector<double>& ground = declared.motion.acceleration;
  TrueActuator actuator(rig, dt);
  TrueSpecimen specimen(rig, k_e, duration);
  std::mt19937_64 rng(rig.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::mt19937_64 link_rng(rig.seed + 1);
  std::deque<double> commands(14, 0.0);  // the 14 ms shift: 14 whole steps
  const std::vector<AnswerUsed> used = answers_used(rig.platform, ground.size(), dt, rig.seed);
  std::vector<double> answered_x(ground.size(), 0.0), answered_f(ground.size(), 0.0);
  double u = 0.0, v = 0.0, a = 0.0, x_m = 0.0, f_m = 0.0, command = 0.0;
  for (std::size_t step = 0; step < ground.size(); ++step) {
    const double t = static_cast<double>(step) * dt;
    if (step > 0) {
      u += dt * v + 0.5 * dt * dt * a;
      command = u;
      commands.push_back(command);
      const double x = actuator.step(commands.front());
      commands.pop_front();
      const double f = specimen.force(x - rig.followed_creep * t / duration, t, dt);
      answered_x[step] = converted(rig.displacement_scale * x + rig.displacement_offset +
                                       rig.displacement_noise * normal(rng),
                                   rig.displacement_range);
      answered_f[step] =
          converted(rig.force_scale * f + rig.force_offset + rig.force_drift * t + rattle(rig, t) +
                        reading_events(rig, t, dt) + rig.force_noise * normal(rng),
                    rig.force_range);
      if (t >= rig.hold_start && t < rig.hold_end) answered_f[step] = answered_f[step - 1];
      x_m = answered_x[static_cast<std::size_t>(used[step].step)];
      f_m = answered_f[static_cast<std::size_t>(used[step].step)];
      const double a_next =
          (-m * ground[step] - c * (v + 0.5 * dt * a) - k_n * u - f_m) / (m + 0.5 * dt * c);
      v += 0.5 * dt * (a + a_next);
      a = a_next;
    }
    entry.Clear();
    runtime::StepRecord& r = *entry.mutable_step();
    r.set_step(static_cast<std::int64_t>(step));
    r.set_time(t);
    r.set_ground_acceleration(ground[step]);
    r.add_displacement(u);
    r.add_velocity(v);
    r.add_acceleration(a);
    r.add_command(command);
    r.add_realised(x_m);
    r.add_measured_force(f_m);
    if (linked) add_link_sample(used[step], step, dt, rig.network, duration, link_rng, r);
    writer.write(entry);
  }
  entry.Clear();
  entry.mutable_footer()->set_ok(true);
  entry.mutable_footer()->set_status("completed");
  writer.write(entry);
  return path;
}

}  // namespace rths::test
