// fourth_set_writer: the fourth blind set (`fourth`), run records of a rig rths never modelled
// and not the paper's frame, written by someone who had read neither identify/ nor the other
// three sets' effects, to score `rths identify` blind (docs/development.md, "Blind records"). Its
// integrator, actuator, specimen and sensors are its own; the framing, record and truth.json are
// blind_record.h's.
//
// Inputs:  --set fourth        the only set it writes
//          --out DIR           where <case>.rthsrec and truth.json go (created)
//          --data DIR          the repository's data/ (the El Centro AT2 and SHA256SUMS)
//          --duration S        seconds of the motion to run (1-39, default 15)
//          --case NAME         write one case only (default: every case of the set)
// Outputs: DIR/<case>.rthsrec  a lockstep run record (format version 2) declaring a 5 ms shift
//          DIR/truth.json      per case: seed, what the rig does, the truth (part, kinds,
//                              frequency, accepted names) and, for an event, window_s: [t0, t1]
// Exit 0 when every record was written, 2 on a usage or input error.
//
// The rig (SI units: m, s, N, kg): a one-storey frame on an elastomeric bearing, m = 3000 kg,
// T = 0.3 s, zeta = 0.04, the bearing (the specimen) alpha = 0.4 of the storey's stiffness,
// dt = 1 ms; declared: the actuator realises the command 5 ms late (case "lag_shift_5ms").
//   k = m (2 pi / T)^2, c = 2 zeta (2 pi / T) m, ks = alpha k (526 kN/m).
//   Explicit Newmark (beta 0, gamma 1/2), step k -> k + 1, F the load cell's reading:
//     u_{k+1} = u_k + dt v_k + dt^2 / 2 a_k                            (the command of k + 1)
//     a_{k+1} = (-m a_g[k+1] - c (v_k + dt/2 a_k) - (1 - alpha) k u_{k+1} - F_{k+1})
//               / (m + c dt / 2)
//     v_{k+1} = v_k + dt / 2 (a_k + a_{k+1})
//   Actuator: the rod x(t) = u(t - d) (linear between samples, d = 5 ms), then the case's effect.
//   Bearing: f = ks x unless the case says. Sensors: the displacement y = x + N(0, 3 um), 16-bit
//   over +-100 mm; the load cell F = f + N(0, 2 N), 16-bit over +-50 kN.
// Record step k: t_k = k dt, u_k, v_k, a_k, command u_k, realised y_k, force F_k; step 0 is the
// rest before the first exchange (y_0 = F_0 = 0).
//
// The cases' effects (each alone; the sag's time scales with --duration, the overload and the
// slip happen when the response first reaches them, and without it the case is a clean rig):
//   string pot rewind   the displacement transducer is a cable (string) pot whose spring rewinds
//                       the cable at most v_r: retracting faster, the reading trails the rod
//                       (y_{k+1} = max(x_{k+1}, y_k - v_r dt)); extending, it follows
//   Mullins bearing     the rubber softens below the largest stretch it has seen (x_m so far):
//                       f = ks x (1 - D(x_m) (1 - (x / x_m)^2)), D = D_0 (1 - exp(-x_m / x_0))
//   cell overload       the first time |f| passes F_o the load cell's flexure yields: its zero
//                       shifts by sgn(f) dF for the rest of the run (an event)
//   clock beat          the controller's and the DAQ's 1 kHz clocks differ by 0.02 %: the delay
//                       saws d(t) = 5 ms + 1 ms frac(t / 5 s + 0.3) (a sample slips every 5 s)
//   servo gain fade     the servo-valve's pilot filter clogs: a first-order lag on the rod whose
//                       time constant grows over the run, tau(t) = 0.5 ms + 2.5 ms t / T_run
//   cell clipping       the load cell's conditioner is on a range too small: F = clamp(f + n, +-F_c)
//   floor impact        a drop-weight test on the same strong floor every 2.5 s (from 1.2 s):
//                       the load cell rings F += A exp(-(t - t_i) / tau) sin(2 pi 31 Hz (t - t_i))
//   infill contact      the frame touches an infill wall after a gap g, pushing one way only:
//                       f = ks x + k_w max(0, x - g)
//   mount slip          the transducer's magnetic base slips on its beam the first time the rod
//                       passes v_s: the reading gains s over 20 ms (half cosine) (an event)
//   excitation sag      a motor starting on the conditioner's supply at 0.5 T_run: the
//                       transducer's gain dips, y = x (1 - 0.04 exp(-(t - t_0) / 1.5 s)) (an event)

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
#include <utility>
#include <vector>

#include "blind_record.h"

namespace {

namespace fs = std::filesystem;

// The declared study (the rig above as rths reads a study); dt, motion and run id are set by
// blind::write_run_record.
const char* const kStudy = R"pb(
  name: "bearing_frame"
  structure {
    sdof { period: 0.3 mass: 3000 }
    damping { modal_zeta: 0.04 }
  }
  integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }
  substructuring {
    experimental_fraction: 0.4
    model { linear {} }
  }
  cases { name: "reference" }
  cases {
    name: "lag_shift_5ms"
    delay { shift { delay: 0.005 } }
  }
  deployment {
    clock: LOCKSTEP
    case_name: "lag_shift_5ms"
    nodes { id: 1 kind: SUBSTRUCTURE }
    nodes { id: 2 kind: ACTUATOR_EMULATOR }
  }
)pb";

struct Rig {
  double m = 3000.0;    // kg
  double period = 0.3;  // s
  double zeta = 0.04;
  double alpha = 0.4;    // the bearing's share of the storey's stiffness
  double dt = 0.001;     // s
  double delay = 0.005;  // s, declared
  double omega = 2.0 * std::numbers::pi / period;
  double k = m * omega * omega;       // N/m
  double c = 2.0 * zeta * omega * m;  // N s/m
  double ks = alpha * k;              // N/m
};

enum class Law {
  clean,
  string_pot_rewind,
  mullins_bearing,
  cell_overload,
  clock_beat,
  servo_gain_fade,
  cell_clipping,
  floor_impact,
  infill_contact,
  mount_slip,
  excitation_sag
};

struct Case {
  std::string name;
  std::uint64_t seed = 0;
  Law law = Law::clean;
  std::string what;
  std::string part;  // empty: a clean rig
  std::vector<std::string> kinds;
  double frequency_hz = 0.0;
  std::vector<std::pair<std::string, std::string>> accepted;
};

// The effects' constants (SI units).
constexpr double kRewindSpeed = 0.09;      // m/s, the string pot's rewind limit
constexpr double kMullinsDepth = 0.35;     // D_0
constexpr double kMullinsScale = 4.0e-3;   // m, x_0
constexpr double kOverloadForce = 4.5e3;   // N, F_o
constexpr double kOverloadShift = 45.0;    // N, dF
constexpr double kBeatPeriod = 5.0;        // s
constexpr double kBeatSpan = 1.0e-3;       // s
constexpr double kFadeStart = 0.5e-3;      // s
constexpr double kFadeGrowth = 2.5e-3;     // s over the run
constexpr double kClipForce = 4.0e3;       // N, F_c
constexpr double kImpactFirst = 1.2;       // s
constexpr double kImpactEvery = 2.5;       // s
constexpr double kImpactForce = 80.0;      // N, A
constexpr double kImpactDecay = 0.06;      // s, tau
constexpr double kImpactRing = 31.0;       // Hz
constexpr double kInfillGap = 5.0e-3;      // m, g
constexpr double kInfillShare = 0.8;       // k_w / ks
constexpr double kSlipSpeed = 0.18;        // m/s, v_s
constexpr double kSlipDistance = 0.35e-3;  // m, s
constexpr double kSlipTime = 0.02;         // s
constexpr double kSagShare = 0.5;          // t_0 / T_run
constexpr double kSagDepth = 0.04;
constexpr double kSagRecovery = 1.5;  // s

std::vector<Case> all_cases() {
  const std::string cell = "load cell 1", rod = "actuator 1", bearing = "specimen 1",
                    sensor = "displacement sensor 1";
  return {
      {"fourth_clean_a", 4101, Law::clean, "a clean rig", "", {}, 0.0, {}},
      {"fourth_clean_b", 4102, Law::clean, "a clean rig, other noise", "", {}, 0.0, {}},
      {"fourth_string_pot_rewind",
       4103,
       Law::string_pot_rewind,
       "the displacement reading trails the rod when it retracts faster than 0.09 m/s",
       sensor,
       {"direction", "amplitude"},
       0.0,
       {}},
      {"fourth_mullins_bearing",
       4104,
       Law::mullins_bearing,
       "the bearing softens below the largest stretch it has seen (Mullins)",
       bearing,
       {"amplitude", "time_varying"},
       0.0,
       {{bearing, "time_varying_stiffness"}}},
      {"fourth_cell_overload",
       4105,
       Law::cell_overload,
       "the load cell's zero shifts 45 N the first time |f| passes 4.5 kN",
       cell,
       {"time_varying"},
       0.0,
       {}},
      {"fourth_clock_beat",
       4106,
       Law::clock_beat,
       "the delay saws from 5 to 6 ms every 5 s (two clocks beating)",
       rod,
       {"periodic", "time_varying"},
       1.0 / kBeatPeriod,
       {{rod, "delay change"}}},
      {"fourth_servo_gain_fade",
       4107,
       Law::servo_gain_fade,
       "a first-order lag on the rod growing from 0.5 to 3 ms over the run",
       rod,
       {"time_varying"},
       0.0,
       {{rod, "first_order"}}},
      {"fourth_cell_clipping",
       4108,
       Law::cell_clipping,
       "the load cell's reading clips at +-4 kN",
       cell,
       {"amplitude"},
       0.0,
       {}},
      {"fourth_floor_impact",
       4109,
       Law::floor_impact,
       "a 31 Hz ring of 80 N in the load cell every 2.5 s (impacts nearby)",
       cell,
       {"periodic", "time_varying"},
       1.0 / kImpactEvery,
       {}},
      {"fourth_infill_contact",
       4110,
       Law::infill_contact,
       "the frame bears on an infill wall past +5 mm, one way only",
       bearing,
       {"direction", "amplitude"},
       0.0,
       {}},
      {"fourth_mount_slip",
       4111,
       Law::mount_slip,
       "the transducer's base slips 0.35 mm the first time the rod passes 0.18 m/s",
       sensor,
       {"time_varying"},
       0.0,
       {}},
      {"fourth_excitation_sag",
       4112,
       Law::excitation_sag,
       "the transducer's gain dips 4 % and recovers over 1.5 s",
       sensor,
       {"time_varying"},
       0.0,
       {}},
  };
}

// The value of samples at the fractional index i - shift (linear between samples; 0 before 0).
double shifted(const std::vector<double>& samples, std::size_t i, double shift) {
  const double at = static_cast<double>(i) - shift;
  if (at <= 0.0) return 0.0;
  const auto j = static_cast<std::size_t>(at);
  const double w = at - static_cast<double>(j);
  return j + 1 <= i ? (1.0 - w) * samples[j] + w * samples[j + 1] : samples[j];
}

// One case's effect on the loop: the actuator's delay and rod, the bearing, the load cell and
// the displacement transducer, each called once per step in time order (they keep state).
class Effect {
 public:
  Effect(const Case& c, const Rig& rig, double duration)
      : case_(c), rig_(rig), duration_(duration) {}

  double delay(double t) const {
    if (case_.law != Law::clock_beat) return rig_.delay;
    const double phase = t / kBeatPeriod + 0.3;
    return rig_.delay + kBeatSpan * (phase - std::floor(phase));
  }

  double rod(double t, double target) {
    if (case_.law != Law::servo_gain_fade) return target;
    const double tau = kFadeStart + kFadeGrowth * t / duration_;
    rod_ += (target - rod_) * (1.0 - std::exp(-rig_.dt / tau));
    return rod_;
  }

  double specimen(double x) {
    const double linear = rig_.ks * x;
    if (case_.law == Law::infill_contact)
      return linear + kInfillShare * rig_.ks * std::max(0.0, x - kInfillGap);
    if (case_.law != Law::mullins_bearing) return linear;
    stretch_ = std::max(stretch_, std::abs(x));
    if (stretch_ <= 0.0) return linear;
    const double depth = kMullinsDepth * (1.0 - std::exp(-stretch_ / kMullinsScale));
    const double r = x / stretch_;
    return linear * (1.0 - depth * (1.0 - r * r));
  }

  double cell(double t, double f, double noise) {
    switch (case_.law) {
      case Law::cell_overload:
        if (!event_ && std::abs(f) > kOverloadForce) {
          event_ = std::make_pair(t, t + rig_.dt);
          cell_shift_ = f > 0.0 ? kOverloadShift : -kOverloadShift;
        }
        return f + noise + cell_shift_;
      case Law::cell_clipping: return std::clamp(f + noise, -kClipForce, kClipForce);
      case Law::floor_impact: return f + noise + impact_ring(t);
      default: return f + noise;
    }
  }

  double sensor(double t, double x) {
    const double last_rod = last_rod_;
    last_rod_ = x;
    switch (case_.law) {
      case Law::string_pot_rewind:
        reading_ = x >= reading_ ? x : std::max(x, reading_ - kRewindSpeed * rig_.dt);
        return reading_;
      case Law::mount_slip:
        if (!event_ && std::abs(x - last_rod) / rig_.dt > kSlipSpeed)
          event_ = std::make_pair(t, t + kSlipTime);
        return x + slip(t);
      case Law::excitation_sag: {
        const double t0 = kSagShare * duration_;
        if (t < t0) return x;
        return x * (1.0 - kSagDepth * std::exp(-(t - t0) / kSagRecovery));
      }
      default: return x;
    }
  }

  // The case's truth; an event the run never reached leaves a clean rig, and says so.
  blind::TruthCase truth() const {
    blind::TruthCase t;
    t.name = case_.name;
    t.set = "fourth";
    t.seed = case_.seed;
    t.what = case_.what;
    t.part = case_.part;
    t.kinds = case_.kinds;
    t.frequency_hz = case_.frequency_hz;
    t.accepted = case_.accepted;
    const bool is_event = case_.law == Law::cell_overload || case_.law == Law::mount_slip;
    if (case_.law == Law::excitation_sag)
      t.window_s = std::make_pair(kSagShare * duration_, kSagShare * duration_ + kSagRecovery);
    if (is_event && event_) t.window_s = event_;
    if (is_event && !event_) {
      t.what += " (never reached in this run: a clean rig)";
      t.part.clear();
      t.kinds.clear();
      t.accepted.clear();
    }
    return t;
  }

 private:
  double impact_ring(double t) const {
    if (t < kImpactFirst) return 0.0;
    const double since = std::fmod(t - kImpactFirst, kImpactEvery);
    return kImpactForce * std::exp(-since / kImpactDecay) *
           std::sin(2.0 * std::numbers::pi * kImpactRing * since);
  }

  double slip(double t) const {
    if (!event_) return 0.0;
    const double s = std::min(1.0, (t - event_->first) / kSlipTime);
    return kSlipDistance * 0.5 * (1.0 - std::cos(std::numbers::pi * s));
  }

  Case case_;
  Rig rig_;
  double duration_;
  double rod_ = 0.0;                                // m, the lagging rod
  double stretch_ = 0.0;                            // m, the largest |x| so far
  double reading_ = 0.0;                            // m, the string pot's
  double last_rod_ = 0.0;                           // m
  double cell_shift_ = 0.0;                         // N
  std::optional<std::pair<double, double>> event_;  // s
};

// v rounded to the nearest of 2^16 levels over [-range, range].
double quantised(double v, double range) {
  const double q = 2.0 * range / 65536.0;
  return std::clamp(std::round(v / q) * q, -range, range - q);
}

// The closed loop of the rig, the case's effect in it; one RecordedStep per motion sample.
std::vector<blind::RecordedStep> simulate(Effect& effect, const Rig& rig,
                                          const std::vector<double>& ag, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> disp_noise(0.0, 3.0e-6), force_noise(0.0, 2.0);
  const double k_num = (1.0 - rig.alpha) * rig.k;
  std::vector<blind::RecordedStep> steps(ag.size());
  std::vector<double> commands(ag.size(), 0.0);
  steps[0].a = -ag[0];
  for (std::size_t i = 0; i + 1 < ag.size(); ++i) {
    const blind::RecordedStep& now = steps[i];
    blind::RecordedStep& next = steps[i + 1];
    const double t = static_cast<double>(i + 1) * rig.dt;
    next.u = now.u + rig.dt * now.v + 0.5 * rig.dt * rig.dt * now.a;
    next.command = next.u;
    commands[i + 1] = next.u;
    const double delay = effect.delay(t);
    const double x = effect.rod(t, shifted(commands, i + 1, delay / rig.dt));
    const double f = effect.specimen(x);
    next.force = quantised(effect.cell(t, f, force_noise(rng)), 50.0e3);
    next.realised = quantised(effect.sensor(t, x) + disp_noise(rng), 0.1);
    next.a = (-rig.m * ag[i + 1] - rig.c * (now.v + 0.5 * rig.dt * now.a) - k_num * next.u -
              next.force) /
             (rig.m + 0.5 * rig.c * rig.dt);
    next.v = now.v + 0.5 * rig.dt * (now.a + next.a);
  }
  return steps;
}

blind::TruthCase write_case(const fs::path& out_dir, const Case& c, const Rig& rig,
                            const blind::Motion& motion, double duration) {
  Effect effect(c, rig, duration);
  blind::RunToRecord run;
  run.run_id = "fourth-" + c.name;
  run.seed = c.seed;
  run.dt = rig.dt;
  run.duration = duration;
  run.motion = &motion;
  run.steps = simulate(effect, rig, motion.accel, c.seed);
  blind::write_run_record(out_dir / (c.name + ".rthsrec"), run, {kStudy, "lag_shift_5ms"});
  return effect.truth();
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<blind::WriterArgs> args =
      blind::writer_args(argc, argv, "fourth_set_writer", {"fourth"});
  if (!args) return 2;
  try {
    const Rig rig;
    const int steps = static_cast<int>(std::lround(args->duration / rig.dt));
    const blind::Motion motion = blind::read_motion(args->data_dir, rig.dt, steps);
    const std::vector<Case> cases = all_cases();
    std::vector<std::string> names;
    for (const Case& c : cases) names.push_back(c.name);
    blind::write_set(*args, names, [&](std::size_t i) {
      return write_case(args->out_dir, cases[i], rig, motion, args->duration);
    });
  } catch (const std::exception& e) {
    std::cerr << "fourth_set_writer: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
