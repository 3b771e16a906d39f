// third_set_writer: the third blind set (`third`), run records of a rig rths never modelled,
// written by someone who had read neither identify/ nor the first two sets' effects, to score
// `rths identify` blind (docs/development.md, "Blind records"). Its integrator, actuator,
// specimen and sensors are its own; the framing, record and truth.json are blind_record.h's.
//
// Inputs:  --set third         the only set it writes
//          --out DIR           where <case>.rthsrec and truth.json go (created)
//          --data DIR          the repository's data/ (the El Centro AT2 and SHA256SUMS)
//          --duration S        seconds of the motion to run (1-39, default 15)
//          --case NAME         write one case only (default: every case of the set)
// Outputs: DIR/<case>.rthsrec  a lockstep run record (format version 2) declaring a 14 ms shift
//          DIR/truth.json      per case: seed, what the rig does, the truth (part, kinds,
//                              frequency, library effects, accepted names) and, for an event,
//                              window_s: [t0, t1], when it happens (s)
// Exit 0 when every record was written, 2 on a usage or input error.
//
// The rig (SI units: m, s, N, kg), the paper's frame (configs/paper_frame.textproto):
//   m = 1000 kg, T = 0.5 s, k = m (2 pi / T)^2, c = 2 zeta (2 pi / T) m, zeta = 0.05; the
//   specimen ks = k / 3, the numerical storey (1 - 1/3) k and all of c; dt = 1 ms.
//   Explicit Newmark (beta 0, gamma 1/2), step k -> k + 1, F the load cell's reading:
//     u_{k+1} = u_k + dt v_k + dt^2 / 2 a_k                            (the command of k + 1)
//     a_{k+1} = (-m a_g[k+1] - c (v_k + dt/2 a_k) - 2/3 k u_{k+1} - F_{k+1}) / (m + c dt / 2)
//     v_{k+1} = v_k + dt / 2 (a_k + a_{k+1})
//   Actuator: the rod x tracks the command shifted by the delay d (14 ms; linear between
//   samples): x(t) = u(t - d), then the case's effect on the rod (below).
//   Specimen: f = ks x unless the case says. Sensors: the displacement y = x + N(0, 2 um), 16-bit
//   over +-50 mm; the load cell F = f + N(0, 0.5 N), 16-bit over +-10 kN.
// Record step k: t_k = k dt, u_k, v_k, a_k, command u_k, realised y_k, force F_k; step 0 is the
// rest before the first exchange (nothing measured yet: y_0 = F_0 = 0).
//
// The cases' effects (each alone; every time is for a 15 s run and scales with --duration):
//   valve flow limit   the rod's speed |dx/dt| <= v0 sqrt(max(0.05, 1 - sgn(dx/dt) f / Fs)):
//                      a servo-valve's flow falls with the load pressure it pushes against
//   pin dead band      a worn pin of total play w: f = ks (x -+ w/2) outside |x| <= w/2, else 0
//   cell clock drift   the load cell samples on its own clock: F_{k} = f(t_k - d_k),
//                      d_k = max(0, ppm 1e-6 t_k + N(0, s_j)) (its lag grows over the run)
//   specimen crack     ks falls by a share the first time |x| passes x_c (an event)
//   damper warming     a fluid damper beside the spring, f += c_d(t) dx/dt, its oil warming:
//                      c_d(t) = c0 (r + (1 - r) exp(-t / t_w))
//   accumulator sag    the actuator's force capacity Fc(t) falls linearly over the run; where
//                      ks |x| would pass it the rod stops at x = +-Fc / ks
//   bolt slip          the first time |f| passes Fslip a bolted joint slips by s over t_s
//                      (half cosine): f = ks (x - s(t)) (an event)
//   held sample        the displacement reading repeats its last value for 200 ms (an event)
//   cross-talk         a neighbouring actuator's cyclic test leaks into the load cell's channel:
//                      F += A sin(2 pi f_x (t - t_on)) from t_on, faded in over 0.5 s
//   asymmetric lag     a single-rod cylinder: a first-order lag on x, time constant tau_out when
//                      extending and tau_in when retracting: dx/dt = (u(t - d) - x) / tau
//   delay jump         the controller's delay d steps from 14 ms to 21 ms mid-run (an event)

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "blind_record.h"

namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
constexpr double kNominalDuration = 15.0;  // s; the cases' times are for a run this long

struct Frame {
  double mass = 1000.0;  // kg
  double period = 0.5;   // s
  double zeta = 0.05;
  double dt = 0.001;  // s
  double omega() const { return 2.0 * kPi / period; }
  double stiffness() const { return mass * omega() * omega(); }   // N/m
  double damping() const { return 2.0 * zeta * omega() * mass; }  // N s/m
  double specimen() const { return stiffness() / 3.0; }           // N/m
};

// What the rig does beside the declared shift; a zero field is an effect that is absent.
struct Rig {
  double flow_velocity = 0.0;  // m/s, v0: the valve's no-load speed limit
  double stall_force = 0.0;    // N, Fs: supply pressure times area
  double dead_band = 0.0;      // m, w: the pin's total play
  double crack_at = 0.0;       // m, x_c
  double crack_loss = 0.0;     // share of ks lost when it cracks
  double clock_ppm = 0.0;      // the load cell's clock error (parts per million)
  double clock_jitter = 0.0;   // s, s_j: rms of its sampling instant
  double damper = 0.0;         // N s/m, c0
  double damper_ratio = 0.0;   // r: c_d over c0 once warm (t >> t_w)
  double warm_time = 0.0;      // s, t_w
  double capacity_start = 0.0, capacity_end = 0.0;       // N, Fc at t = 0 and at the end
  double slip_force = 0.0, slip = 0.0, slip_time = 0.0;  // N, m, s
  double hold_at = 0.0, hold_for = 0.0;                  // s
  double crosstalk = 0.0, crosstalk_hz = 0.0, crosstalk_from = 0.0;  // N, Hz, s
  double tau_out = 0.0, tau_in = 0.0;                                // s
  double jump_at = 0.0, jump_delay = 0.0;                            // s, s
};

struct Case {
  std::string name;
  std::uint64_t seed = 0;
  Rig rig;
  blind::TruthCase truth;    // window_s filled from the run for an event
  double window_span = 0.0;  // s after the event that window_s covers; 0: not an event
};

// ---------- the rig's parts ----------

double quantised(double value, double range) {
  const double quantum = 2.0 * range / 65536.0;
  return std::clamp(std::round(value / quantum) * quantum, -range, range - quantum);
}

// The history h (one sample per dt) at time s, linear between samples, h[0] before the start.
double at_time(const std::vector<double>& h, double s, double dt) {
  if (s <= 0.0) return h.front();
  const double pos = s / dt;
  const auto i = static_cast<std::size_t>(pos);
  if (i + 1 >= h.size()) return h.back();
  const double w = pos - static_cast<double>(i);
  return (1.0 - w) * h[i] + w * h[i + 1];
}

// The state the rig carries from step to step, and when an event happened (s).
struct RigState {
  double rod = 0.0;    // m, x
  double force = 0.0;  // N, f: the specimen's true force
  double slip_start = -1.0;
  double slip_sign = 0.0;
  bool cracked = false;
  double held = 0.0;  // m, the reading a stuck sensor repeats
  std::optional<double> event_at;
};

// The rod at t from the commands so far (u_hist[j] = u_j): the delayed command, then the
// case's lag, flow limit or force capacity.
double rod_position(const Rig& rig, const Frame& f, const std::vector<double>& u_hist, double t,
                    double duration, RigState& s) {
  const double delay = (rig.jump_at > 0.0 && t >= rig.jump_at) ? rig.jump_delay : 0.014;
  if (rig.jump_at > 0.0 && t >= rig.jump_at && !s.event_at) s.event_at = rig.jump_at;
  const double target = at_time(u_hist, t - delay, f.dt);
  double x = target;
  if (rig.tau_out > 0.0) {
    const double tau = target >= s.rod ? rig.tau_out : rig.tau_in;
    x = s.rod + (1.0 - std::exp(-f.dt / tau)) * (target - s.rod);
  }
  if (rig.flow_velocity > 0.0) {
    const double demand = (x - s.rod) / f.dt;
    const double sign = demand >= 0.0 ? 1.0 : -1.0;
    const double limit =
        rig.flow_velocity * std::sqrt(std::max(0.05, 1.0 - sign * s.force / rig.stall_force));
    x = s.rod + std::clamp(demand, -limit, limit) * f.dt;
  }
  if (rig.capacity_start > 0.0) {
    const double capacity =
        rig.capacity_start + (rig.capacity_end - rig.capacity_start) * t / duration;
    const double reach = capacity / f.specimen();
    x = std::clamp(x, -reach, reach);
  }
  return x;
}

// The specimen's true force (N) at the rod x (m), the rod having moved from s.rod over dt.
double specimen_force(const Rig& rig, const Frame& f, double x, double t, RigState& s) {
  double ks = f.specimen();
  if (rig.crack_at > 0.0 && !s.cracked && std::abs(x) > rig.crack_at) {
    s.cracked = true;
    s.event_at = t;
  }
  if (s.cracked) ks *= 1.0 - rig.crack_loss;
  double deformation = x;
  if (rig.dead_band > 0.0) {
    const double half = rig.dead_band / 2.0;
    deformation = x > half ? x - half : (x < -half ? x + half : 0.0);
  }
  if (rig.slip_force > 0.0) {
    if (s.slip_start < 0.0 && std::abs(ks * x) > rig.slip_force) {
      s.slip_start = t;
      s.slip_sign = x > 0.0 ? 1.0 : -1.0;
      s.event_at = t;
    }
    if (s.slip_start >= 0.0) {
      const double phase = std::min(1.0, (t - s.slip_start) / rig.slip_time);
      deformation -= s.slip_sign * rig.slip * (1.0 - std::cos(kPi * phase)) / 2.0;
    }
  }
  double force = ks * deformation;
  if (rig.damper > 0.0) {
    const double c =
        rig.damper * (rig.damper_ratio + (1.0 - rig.damper_ratio) * std::exp(-t / rig.warm_time));
    force += c * (x - s.rod) / f.dt;
  }
  return force;
}

// The load cell's reading (N) at t of the true forces so far (f_hist[j] at t_j).
double cell_reading(const Rig& rig, const Frame& f, const std::vector<double>& f_hist, double t,
                    std::mt19937_64& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  double force = f_hist.back();
  if (rig.clock_ppm > 0.0) {
    const double lag = std::max(0.0, rig.clock_ppm * 1e-6 * t + rig.clock_jitter * unit(rng));
    force = at_time(f_hist, t - lag, f.dt);
  }
  if (rig.crosstalk > 0.0 && t > rig.crosstalk_from) {
    const double since = t - rig.crosstalk_from;
    force +=
        rig.crosstalk * std::min(1.0, since / 0.5) * std::sin(2.0 * kPi * rig.crosstalk_hz * since);
  }
  return quantised(force + 0.5 * unit(rng), 10.0e3);
}

// The displacement transducer's reading (m) of the rod x at t.
double displacement_reading(const Rig& rig, double x, double t, RigState& s, std::mt19937_64& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  const double read = quantised(x + 2.0e-6 * unit(rng), 0.05);
  if (rig.hold_for > 0.0 && t >= rig.hold_at && t < rig.hold_at + rig.hold_for) {
    if (!s.event_at) s.event_at = t;
    return s.held;
  }
  s.held = read;
  return read;
}

// ---------- the closed loop ----------

struct Run {
  std::vector<blind::RecordedStep> steps;
  std::optional<double> event_at;  // s
};

Run simulate(const Frame& f, const Rig& rig, const std::vector<double>& ground, double duration,
             std::uint64_t seed) {
  const double m = f.mass, c = f.damping(), k_num = f.stiffness() - f.specimen(), dt = f.dt;
  const std::size_t n = ground.size();
  std::mt19937_64 rng(seed);
  Run run;
  run.steps.resize(n);
  std::vector<double> u_hist{0.0}, f_hist{0.0};
  RigState state;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const blind::RecordedStep& now = run.steps[k];
    const double t = static_cast<double>(k + 1) * dt;
    blind::RecordedStep& next = run.steps[k + 1];
    next.u = now.u + dt * now.v + dt * dt / 2.0 * now.a;
    next.command = next.u;
    u_hist.push_back(next.u);
    const double x = rod_position(rig, f, u_hist, t, duration, state);
    const double force = specimen_force(rig, f, x, t, state);
    state.rod = x;
    state.force = force;
    f_hist.push_back(force);
    next.force = cell_reading(rig, f, f_hist, t, rng);
    next.realised = displacement_reading(rig, x, t, state, rng);
    next.a = (-m * ground[k + 1] - c * (now.v + dt / 2.0 * now.a) - k_num * next.u - next.force) /
             (m + c * dt / 2.0);
    next.v = now.v + dt / 2.0 * (now.a + next.a);
  }
  run.event_at = state.event_at;
  return run;
}

// ---------- the cases ----------

// What every case's truth shares: the set, and the names that describe what every case's rig
// does (its sensors' noise), accepted wherever they are named.
blind::TruthCase truth_of(const std::string& what, const std::string& part,
                          std::vector<std::string> kinds) {
  blind::TruthCase truth;
  truth.set = "third";
  truth.what = what;
  truth.part = part;
  truth.kinds = std::move(kinds);
  truth.accepted = {{"load cell 1", "noise"}, {"displacement sensor 1", "noise"}};
  return truth;
}

Case make_case(const std::string& name, std::uint64_t seed, const Rig& rig, blind::TruthCase truth,
               double window_span = 0.0) {
  truth.name = name;
  truth.seed = seed;
  return {name, seed, rig, std::move(truth), window_span};
}

// Sizes below are set against the clean rig's response to the 15 s motion: peak |x| 18.4 mm
// (about 9 s in; 9.5 mm by 7 s), |f| 970 N, |dx/dt| 0.21 m/s. `at` is s per nominal s
// (duration / 15 s).
std::vector<Case> actuator_cases(double at) {
  Rig valve;
  valve.flow_velocity = 0.16;
  valve.stall_force = 1500.0;
  auto valve_truth = truth_of(
      "servo-valve flow limit, 0.16 m/s unloaded, falling with the load "
      "pressure",
      "actuator 1", {"amplitude", "direction"});
  valve_truth.library = {{"actuator 1", "velocity_saturation"}};
  Rig sag;
  sag.capacity_start = 1400.0;
  sag.capacity_end = 500.0;
  Rig asym;
  asym.tau_out = 0.004;
  asym.tau_in = 0.012;
  auto asym_truth = truth_of("single-rod cylinder: lag 4 ms extending, 12 ms retracting",
                             "actuator 1", {"direction"});
  asym_truth.accepted.push_back({"actuator 1", "first_order"});
  Rig jump;
  jump.jump_at = 8.0 * at;
  jump.jump_delay = 0.019;
  auto jump_truth =
      truth_of("the controller's delay steps from 14 ms to 19 ms", "actuator 1", {"time_varying"});
  jump_truth.accepted.push_back({"actuator 1", "time_varying_delay"});
  jump_truth.accepted.push_back({"actuator 1", "delay change"});
  return {make_case("third_valve_flow_limit", 3103, valve, valve_truth),
          make_case("third_accumulator_sag", 3108, sag,
                    truth_of("accumulator pressure sags: force capacity 1.4 kN falling to 0.5 kN",
                             "actuator 1", {"amplitude", "time_varying"})),
          make_case("third_asymmetric_lag", 3112, asym, asym_truth),
          make_case("third_delay_jump", 3113, jump, jump_truth, 0.05)};
}

std::vector<Case> specimen_cases(double at) {
  Rig pin;
  pin.dead_band = 1.2e-3;
  auto pin_truth = truth_of("1.2 mm of play in the specimen's pin", "specimen 1", {"amplitude"});
  pin_truth.accepted.push_back({"specimen 1", "backlash"});
  Rig crack;
  crack.crack_at = 0.012;
  crack.crack_loss = 0.35;
  auto crack_truth = truth_of("specimen cracks past 12 mm, losing 35 % of its stiffness",
                              "specimen 1", {"time_varying"});
  crack_truth.accepted.push_back({"specimen 1", "time_varying_stiffness"});
  crack_truth.accepted.push_back({"specimen 1", "stiffness change"});
  Rig damper;
  damper.damper = 1200.0;
  damper.damper_ratio = 0.4;
  damper.warm_time = 6.0 * at;
  auto damper_truth =
      truth_of("fluid damper beside the specimen, its oil warming", "specimen 1", {"time_varying"});
  damper_truth.library = {{"specimen 1", "damping"}};
  Rig slip;
  slip.slip_force = 600.0;
  slip.slip = 0.8e-3;
  slip.slip_time = 0.03;
  return {make_case("third_pin_dead_band", 3104, pin, pin_truth),
          make_case("third_specimen_crack", 3106, crack, crack_truth, 0.05),
          make_case("third_damper_warming", 3107, damper, damper_truth),
          make_case("third_bolt_slip", 3109, slip,
                    truth_of("a bolted joint slips 0.8 mm over 30 ms when the force passes 600 N",
                             "specimen 1", {"time_varying"}),
                    0.03)};
}

std::vector<Case> sensor_cases(double at) {
  Rig clock;
  clock.clock_ppm = 600.0;
  clock.clock_jitter = 1.5e-4;
  auto clock_truth = truth_of("load cell on its own clock, 600 ppm slow, 0.15 ms jitter",
                              "load cell 1", {"time_varying"});
  clock_truth.accepted.push_back({"load cell 1", "time_varying_delay"});
  Rig hold;
  hold.hold_at = 7.3 * at;
  hold.hold_for = 0.2;
  Rig talk;
  talk.crosstalk = 30.0;
  talk.crosstalk_hz = 0.9;
  talk.crosstalk_from = 2.5 * at;
  auto talk_truth = truth_of("a neighbouring actuator's 0.9 Hz test leaks 30 N into the cell",
                             "load cell 1", {"periodic"});
  talk_truth.frequency_hz = 0.9;
  return {make_case("third_cell_clock_drift", 3105, clock, clock_truth),
          make_case("third_held_sample", 3110, hold,
                    truth_of("displacement reading stuck on one sample for 200 ms",
                             "displacement sensor 1", {"time_varying"}),
                    0.2),
          make_case("third_crosstalk", 3111, talk, talk_truth)};
}

// Every case of a run `duration` s long, two clean ones first.
std::vector<Case> all_cases(double duration) {
  const double at = duration / kNominalDuration;
  std::vector<Case> cases = {
      make_case("third_clean_a", 3101, {}, truth_of("noise and converters only", "", {})),
      make_case("third_clean_b", 3102, {},
                truth_of("noise and converters only, another seed", "", {}))};
  for (auto part : {actuator_cases(at), specimen_cases(at), sensor_cases(at)})
    cases.insert(cases.end(), part.begin(), part.end());
  return cases;
}

// ---------- writing ----------

// Writes one case's record and returns its truth, the event's window from the run; a case whose
// event the run never reached (a short --duration) is clean and its truth says so.
blind::TruthCase write_case(const fs::path& out_dir, const Case& c, const Frame& f,
                            const blind::Motion& motion, double duration) {
  Run run = simulate(f, c.rig, motion.accel, duration, c.seed);
  for (const blind::RecordedStep& s : run.steps)
    if (std::abs(s.u) > 0.045)
      throw std::runtime_error(c.name +
                               ": the response passes 45 mm, near the transducer's 50 mm "
                               "range; the record would clip");
  blind::RunToRecord to_record{"blind-" + c.name, c.seed,  f.dt,
                               duration,          &motion, std::move(run.steps)};
  blind::write_run_record(out_dir / (c.name + ".rthsrec"), to_record);
  blind::TruthCase truth = c.truth;
  if (c.window_span > 0.0 && run.event_at) {
    truth.window_s = std::make_pair(*run.event_at, *run.event_at + c.window_span);
  } else if (c.window_span > 0.0) {
    truth = truth_of(c.truth.what + " (not reached in this run: clean)", "", {});
    truth.name = c.name;
    truth.seed = c.seed;
  }
  return truth;
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<blind::WriterArgs> args =
      blind::writer_args(argc, argv, "third_set_writer", {"third"});
  if (!args) return 2;
  const std::string &out_dir = args->out_dir, &data_dir = args->data_dir;
  const double duration = args->duration;
  try {
    const Frame f;
    const int steps = static_cast<int>(std::lround(duration / f.dt));
    const blind::Motion motion = blind::read_motion(data_dir, f.dt, steps);
    const std::vector<Case> cases = all_cases(duration);
    std::vector<std::string> names;
    for (const Case& c : cases) names.push_back(c.name);
    blind::write_set(*args, names, [&](std::size_t i) {
      return write_case(out_dir, cases[i], f, motion, duration);
    });
  } catch (const std::exception& e) {
    std::cerr << "third_set_writer: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
