// fifth_set_writer: the `fifth` blind set (docs/development.md, "Blind records"), written by a
// fifth hand that read neither identify/ nor the other sets' effects: run records of a
// single-storey steel frame with a buckling-restrained brace as the experimental element, on a
// rig whose integrator, servo, brace and sensors are all its own.
//
// Inputs: --set fifth --out DIR --data DATA_DIR [--duration S] [--case NAME] (blind_record.h);
//   the 1940 El Centro record data/ground_motions/IELC180.AT2 (values in g at 10 ms), linearly
//   interpolated to the run's dt.
// Outputs: DIR/<case>.rthsrec (one lockstep run each) and DIR/truth.json (blind_record.h).
//
// The rig (SI units): m = 12000 kg, T = 0.8 s, k = m (2 pi / T)^2 = 740.2 kN/m, 3 % damping
// c = 2 zeta sqrt(k m); the brace is 60 % of the storey, k_e = 0.6 k = 444.1 kN/m, the frame
// k_n = k - k_e; dt = 2 ms. The study declares exactly this, a linear brace and no actuator
// stage at all (case "as_built"): a perfect servo.
//   Chen-Ricles: alpha = 4 m / (4 m + 2 dt c + dt^2 k);
//     u_{k+1} = u_k + dt v_k + alpha dt^2 a_k,  v_{k+1} = v_k + alpha dt a_k,
//     command c_{k+1} = u_{k+1};  the servo drives the rod to x_{k+1}; the brace returns
//     f_{k+1}; the DAQ reads y_{k+1} (LVDT) and F_{k+1} (load cell), and
//     m a_{k+1} = -m a_g(t_{k+1}) - c v_{k+1} - k_n u_{k+1} - F_{k+1}.
//   Clean servo: x = c. Brace: f = k_e x. LVDT: y = x + 2 um noise, 16 bits over +-0.2 m;
//   load cell: F = f + 1.5 N noise, 16 bits over +-100 kN. Noise seeded by the case's seed.
// Cases and their laws (x the rod, t the time; each checked by fifth_set_writer_test.py):
//   fifth_clean_a, fifth_clean_b  the rig as declared, two seeds.
//   fifth_valve_lag               the servo realises the command 3 steps (6 ms) late:
//                                 x_k = c_{k-3}; nothing declared it.
//   fifth_valve_rate_limit        the servo valve's flow caps the rod's speed at 0.30 m/s:
//                                 x_k = x_{k-1} + clamp(c_k - x_{k-1}, +-0.30 dt).
//   fifth_clevis_play             a worn clevis pin between rod and brace, 0.6 mm of play
//                                 (the LVDT on the brace): the brace end follows the rod by a
//                                 play operator of half-width 0.3 mm.
//   fifth_brace_yield             the brace's core yields at 12 mm, 2 % hardening (kinematic,
//                                 bilinear): f = k_e (x - p), |f - 0.02 k_e x| capped.
//   fifth_gusset_crack            a crack grows in the gusset with the brace's travel s (m of
//                                 |dx|): f = k_e x (1 - 0.35 (1 - exp(-s / 1.5 m))).
//   fifth_lvdt_bracket_creep      the LVDT's bracket creeps 1.5 mm over the run, linear in t;
//                                 the servo holds the reading, so the brace sees x = y - drift:
//                                 F = k_e (y - 1.5 mm t / duration).
//   fifth_force_sample_held       the load cell's channel holds one reading for 0.3 s from
//                                 6.0 s (window), and the integrator uses the held value.
//   fifth_pump_pressure_dip       the pump's pressure dips from 4 to 6 s (window): the
//                                 actuator cannot push the brace past 20 kN, |x| <= 20 kN / k_e.
//   fifth_welder_spikes           an arc welder nearby puts 9 spikes of 1.5 mm on the recorded
//                                 LVDT channel between 12.0 and 12.5 s (window); the servo's
//                                 own conditioner is shielded, so the loop is untouched.
//   fifth_mains_hum               a ground loop adds 50 Hz hum, 30 N, to the load cell.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <exception>
#include <fstream>
#include <iostream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "blind_record.h"

namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 0.002;        // s
constexpr double kMass = 12000.0;    // kg
constexpr double kPeriod = 0.8;      // s
constexpr double kZeta = 0.03;       // damping ratio
constexpr double kBraceShare = 0.6;  // k_e / k
constexpr double kStiffness = kMass * (2.0 * kPi / kPeriod) * (2.0 * kPi / kPeriod);  // N/m
constexpr double kBrace = kBraceShare * kStiffness;                                   // N/m
constexpr double kLvdtNoise = 2.0e-6;           // m, one sigma
constexpr double kLvdtQuantum = 0.4 / 65536;    // m, 16 bits over +-0.2 m
constexpr double kCellNoise = 1.5;              // N, one sigma
constexpr double kCellQuantum = 2.0e5 / 65536;  // N, 16 bits over +-100 kN

const char* const kMotionFile = "IELC180.AT2";

// The study the runs declare: the frame, the linear brace, no actuator stage.
const char* const kStudy = R"pb(
  name: "braced_frame"
  structure {
    sdof { period: 0.8 mass: 12000 }
    damping { modal_zeta: 0.03 }
  }
  integrator { kind: CHEN_RICLES dt: 0.002 }
  substructuring {
    experimental_fraction: 0.6
    model { linear {} }
  }
  cases { name: "as_built" }
  deployment {
    clock: LOCKSTEP
    case_name: "as_built"
    nodes { id: 1 kind: SUBSTRUCTURE }
    nodes { id: 2 kind: ACTUATOR_EMULATOR }
  }
)pb";

// A window [start, end) in seconds; empty when end <= start.
struct Window {
  double start = 0.0;
  double end = 0.0;
  bool holds(double t) const { return t >= start && t < end; }
};

// What each case changes on the rig; the defaults are the rig as declared.
struct RigEffects {
  int lag_steps = 0;                // servo transport lag, steps
  double max_speed = 0.0;           // m/s, 0: none
  double play_half_width = 0.0;     // m, clevis play on each side
  double yield_displacement = 0.0;  // m, 0: the brace stays elastic
  double crack_depth = 0.0;         // share of k_e lost at long travel
  double lvdt_creep = 0.0;          // m over the run
  Window force_held;                // the load cell's reading held
  Window pressure_dip;              // the actuator's force capped
  double capped_force = 0.0;        // N, in pressure_dip
  Window spikes;                    // spikes on the recorded LVDT channel
  double hum_amplitude = 0.0;       // N, 50 Hz on the load cell
};

constexpr double kHardening = 0.02;   // post-yield ratio of the yielding brace
constexpr double kCrackTravel = 1.5;  // m of travel for the crack's e-fold
constexpr int kSpikeCount = 9;
constexpr double kSpikeHeight = 1.5e-3;  // m
constexpr double kHumHz = 50.0;

// The servo and the clevis: command c_k (m) -> the brace end x_k (m). The LVDT on the brace reads
// x_k + creep(t) before noise; the servo closes its loop on that reading, so the brace end falls
// short of the target by the creep.
class Servo {
 public:
  explicit Servo(const RigEffects& fx) : fx_(fx) {}

  // x_k for the command at step k (t = k dt), given the run's duration (s).
  double brace_end(double command, int k, double duration) {
    history_.push_back(command);
    if (static_cast<int>(history_.size()) > fx_.lag_steps + 1) history_.pop_front();
    double target =
        history_.size() == static_cast<std::size_t>(fx_.lag_steps + 1) ? history_.front() : 0.0;
    const double t = k * kDt;
    target -= creep(t, duration);
    if (fx_.max_speed > 0.0)
      target = rod_ + std::clamp(target - rod_, -fx_.max_speed * kDt, fx_.max_speed * kDt);
    if (fx_.pressure_dip.holds(t)) {
      const double reach = fx_.capped_force / kBrace;
      target = std::clamp(target, -reach, reach);
    }
    rod_ = target;
    if (fx_.play_half_width > 0.0)
      end_ = std::clamp(end_, rod_ - fx_.play_half_width, rod_ + fx_.play_half_width);
    else
      end_ = rod_;
    return end_;
  }

  double creep(double t, double duration) const { return fx_.lvdt_creep * t / duration; }

 private:
  const RigEffects& fx_;
  std::deque<double> history_;
  double rod_ = 0.0;
  double end_ = 0.0;
};

// The brace: its end x (m) -> force (N); elastic, yielding (bilinear, kinematic hardening) or
// cracking with travel.
class Brace {
 public:
  explicit Brace(const RigEffects& fx) : fx_(fx) {}

  double force(double x) {
    travel_ += std::abs(x - last_);
    last_ = x;
    if (fx_.yield_displacement > 0.0) return yielding(x);
    const double cracked = fx_.crack_depth * (1.0 - std::exp(-travel_ / kCrackTravel));
    return kBrace * x * (1.0 - cracked);
  }

 private:
  // Bilinear: the elastic part k_e (1 - b) (x - p) is capped at k_e (1 - b) x_y, the plastic
  // drift p following, plus b k_e x.
  double yielding(double x) {
    const double cap = (1.0 - kHardening) * kBrace * fx_.yield_displacement;
    const double elastic = (1.0 - kHardening) * kBrace * (x - plastic_);
    if (std::abs(elastic) > cap) plastic_ = x - std::copysign(fx_.yield_displacement, elastic);
    return (1.0 - kHardening) * kBrace * (x - plastic_) + kHardening * kBrace * x;
  }

  const RigEffects& fx_;
  double travel_ = 0.0;
  double last_ = 0.0;
  double plastic_ = 0.0;
};

double quantised(double value, double quantum) { return quantum * std::round(value / quantum); }

// The DAQ: what the LVDT and the load cell record at step k, with their noise, effects and
// converters; the held reading and the spikes are its own faults.
class Daq {
 public:
  Daq(const RigEffects& fx, std::uint64_t seed) : fx_(fx), rng_(seed) {
    std::uniform_real_distribution<double> when(fx.spikes.start, fx.spikes.end);
    for (int i = 0; i < kSpikeCount && fx.spikes.end > fx.spikes.start; ++i)
      spike_steps_.push_back(static_cast<int>(std::lround(when(rng_) / kDt)));
  }

  double lvdt(double reading, int k) {
    double y = reading + kLvdtNoise * noise_(rng_);
    if (std::find(spike_steps_.begin(), spike_steps_.end(), k) != spike_steps_.end())
      y += (k % 2 ? 1.0 : -1.0) * kSpikeHeight;
    return quantised(y, kLvdtQuantum);
  }

  double load_cell(double force, int k) {
    const double t = k * kDt;
    if (fx_.force_held.holds(t) && k > 0) return last_reading_;
    const double hum = fx_.hum_amplitude * std::sin(2.0 * kPi * kHumHz * t + 0.7);
    last_reading_ = quantised(force + hum + kCellNoise * noise_(rng_), kCellQuantum);
    return last_reading_;
  }

 private:
  const RigEffects& fx_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  std::vector<int> spike_steps_;
  double last_reading_ = 0.0;  // N, what a held channel repeats
};

// The closed loop over the motion (see the header's equations), one RecordedStep per sample.
std::vector<blind::RecordedStep> run_rig(const RigEffects& fx, const blind::Motion& motion,
                                         std::uint64_t seed, double duration) {
  const double damping = 2.0 * kZeta * std::sqrt(kStiffness * kMass);
  const double frame = kStiffness - kBrace;
  const double alpha = 4.0 * kMass / (4.0 * kMass + 2.0 * kDt * damping + kDt * kDt * kStiffness);
  Servo servo(fx);
  Brace brace(fx);
  Daq daq(fx, seed);
  std::vector<blind::RecordedStep> steps;
  blind::RecordedStep s;
  s.a = -motion.accel[0];
  steps.push_back(s);
  for (std::size_t k = 1; k < motion.accel.size(); ++k) {
    blind::RecordedStep next;
    next.u = s.u + kDt * s.v + alpha * kDt * kDt * s.a;
    next.v = s.v + alpha * kDt * s.a;
    next.command = next.u;
    const int step = static_cast<int>(k);
    const double x = servo.brace_end(next.command, step, duration);
    next.realised = daq.lvdt(x + servo.creep(step * kDt, duration), step);
    next.force = daq.load_cell(brace.force(x), step);
    next.a = -motion.accel[k] - (damping * next.v + frame * next.u + next.force) / kMass;
    steps.push_back(next);
    s = next;
  }
  return steps;
}

// One case: its rig, its truth (set, seed, what, part, kinds, frequency, library, accepted,
// window), filled in by the add_*_cases that hold it.
struct FifthCase {
  RigEffects fx;
  blind::TruthCase truth;
};

// The parts as the run's report names them: the actuator (command -> measured), the brace
// (measured -> force) and the two sensors.
const char* const kActuator = "actuator 1";
const char* const kBracePart = "specimen 1";
const char* const kCell = "load cell 1";
const char* const kLvdt = "displacement sensor 1";

FifthCase case_named(const std::string& name, std::uint64_t seed, const std::string& what) {
  FifthCase c;
  c.truth.name = name;
  c.truth.set = "fifth";
  c.truth.seed = seed;
  c.truth.what = what;
  return c;
}

// The servo, the valve, the clevis and the pump.
void add_actuator_cases(std::vector<FifthCase>& all) {
  const std::string actuator = kActuator;
  all.push_back(case_named("fifth_valve_lag", 503, "the servo realises the command 6 ms late"));
  all.back().fx.lag_steps = 3;
  all.back().truth.part = actuator;
  all.back().truth.kinds = {"lag", "velocity"};
  all.back().truth.library = {{actuator, "delay"}};
  all.back().truth.accepted = {{actuator, "delay change"}};
  all.push_back(
      case_named("fifth_valve_rate_limit", 504, "the servo valve caps the rod at 0.30 m/s"));
  all.back().fx.max_speed = 0.30;
  all.back().truth.part = actuator;
  all.back().truth.kinds = {"amplitude", "velocity"};
  all.back().truth.library = {{actuator, "velocity_saturation"}};
  all.push_back(case_named("fifth_clevis_play", 505, "0.6 mm of play in the clevis pin"));
  all.back().fx.play_half_width = 0.3e-3;
  all.back().truth.part = actuator;
  all.back().truth.kinds = {"direction", "amplitude"};
  all.back().truth.library = {{actuator, "backlash"}};
  all.push_back(case_named("fifth_pump_pressure_dip", 510, "the pump's pressure dips: 20 kN cap"));
  all.back().fx.pressure_dip = {4.0, 6.0};
  all.back().fx.capped_force = 20e3;
  all.back().truth.part = actuator;
  all.back().truth.kinds = {"capacity_drop", "amplitude", "time_varying"};
  all.back().truth.accepted = {{actuator, "stroke_limit"}};
  all.back().truth.window_s = {{4.0, 6.0}};
}

// The brace itself.
void add_brace_cases(std::vector<FifthCase>& all) {
  const std::string brace = kBracePart;
  all.push_back(case_named("fifth_brace_yield", 506, "the brace's core yields at 12 mm"));
  all.back().fx.yield_displacement = 12e-3;
  all.back().truth.part = brace;
  all.back().truth.kinds = {"amplitude"};
  all.back().truth.library = {{brace, "bilinear"}};
  all.back().truth.accepted = {{brace, "bouc_wen"}, {brace, "elastoplastic"}};
  all.push_back(
      case_named("fifth_gusset_crack", 507, "a gusset crack softens the brace with travel"));
  all.back().fx.crack_depth = 0.35;
  all.back().truth.part = brace;
  all.back().truth.kinds = {"time_varying"};
  all.back().truth.accepted = {{brace, "time_varying_stiffness"}};
}

// The LVDT, the load cell and the DAQ that reads them.
void add_sensor_cases(std::vector<FifthCase>& all) {
  const std::string brace = kBracePart, cell = kCell, lvdt = kLvdt;
  all.push_back(case_named("fifth_lvdt_bracket_creep", 508, "the LVDT's bracket creeps 1.5 mm"));
  all.back().fx.lvdt_creep = 1.5e-3;
  all.back().truth.part = lvdt;
  all.back().truth.kinds = {"time_varying"};
  all.back().truth.accepted = {
      {lvdt, "offset_drift"}, {brace, "offset_drift"}, {cell, "offset_drift"}};
  all.push_back(case_named("fifth_force_sample_held", 509, "the load cell holds a reading 0.3 s"));
  all.back().fx.force_held = {6.0, 6.3};
  all.back().truth.part = cell;
  all.back().truth.kinds = {"held", "time_varying"};
  all.back().truth.window_s = {{6.0, 6.3}};
  all.push_back(case_named("fifth_welder_spikes", 511, "9 welder spikes on the recorded LVDT"));
  all.back().fx.spikes = {12.0, 12.5};
  all.back().truth.part = lvdt;
  all.back().truth.kinds = {"spike", "time_varying"};
  all.back().truth.window_s = {{12.0, 12.5}};
  all.push_back(case_named("fifth_mains_hum", 512, "50 Hz ground-loop hum on the load cell"));
  all.back().fx.hum_amplitude = 30.0;
  all.back().truth.part = cell;
  all.back().truth.kinds = {"periodic"};
  all.back().truth.frequency_hz = kHumHz;
}

std::vector<FifthCase> cases() {
  std::vector<FifthCase> all;
  all.push_back(case_named("fifth_clean_a", 501, "the braced frame as declared"));
  all.push_back(case_named("fifth_clean_b", 502, "the braced frame as declared, another seed"));
  add_actuator_cases(all);
  add_brace_cases(all);
  add_sensor_cases(all);
  return all;
}

}  // namespace

int main(int argc, char** argv) {
  const auto args = blind::writer_args(argc, argv, "fifth_set_writer", {"fifth"});
  if (!args) return 2;
  try {
    const int steps = static_cast<int>(std::lround(args->duration / kDt)) + 1;
    const blind::Motion motion = blind::read_motion(args->data_dir, kDt, steps, kMotionFile);
    const std::vector<FifthCase> all = cases();
    std::vector<std::string> names;
    for (const FifthCase& c : all) names.push_back(c.truth.name);
    blind::write_set(*args, names, [&](std::size_t i) {
      const FifthCase& c = all[i];
      blind::RunToRecord run{"fifth-" + c.truth.name,
                             c.truth.seed,
                             kDt,
                             args->duration,
                             &motion,
                             run_rig(c.fx, motion, c.truth.seed, args->duration)};
      blind::write_run_record(fs::path(args->out_dir) / (c.truth.name + ".rthsrec"), run,
                              {kStudy, "as_built"});
      return c.truth;
    });
  } catch (const std::exception& e) {
    std::cerr << "fifth_set_writer: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
