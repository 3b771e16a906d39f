// blind_record_writer: run records of a rig rths never modelled, written as a lab would write
// them from docs/records.md ("Format") and proto/runtime.proto (RecordEntry) alone, to score
// `rths identify` blind (docs/development.md, "Blind records"). It shares no code with identify/,
// core/ or runtime/: its own integrator, actuator, specimen and sensors; the framing, CRC-32C,
// record and truth.json in blind_record.h, shared with third_set_writer.
//
// Inputs:  --set tune|report   which held-apart set of cases to write (cases below)
//          --out DIR           where <case>.rthsrec and truth.json go (created)
//          --data DIR          the repository's data/ (the El Centro AT2 and SHA256SUMS)
//          --duration S        seconds of the motion to run (default 15)
//          --case NAME         write one case only (default: every case of the set)
// Outputs: DIR/<case>.rthsrec  a lockstep run record (format version 2)
//          DIR/truth.json      per case: seed, what the rig does and the truth: part, description
//                              kinds, frequency (Hz), the library effects in the rig (to be named)
//                              and names that describe the effect itself (accepted, not required)
// Exit 0 when every record was written, 2 on a usage or input error.
//
// The rig (SI units: m, s, N, kg), the paper's frame (configs/paper_frame.textproto):
//   m = 1000 kg, T = 0.5 s, k = m (2 pi / T)^2, c = 2 zeta omega m with zeta = 0.05, the
//   specimen alpha = 1/3 of k, the numerical storey (1 - alpha) k and all of c, dt = 1 ms.
//   Integrator (explicit Newmark, beta = 0, gamma = 1/2), step k -> k + 1:
//     u_{k+1} = u_k + dt v_k + dt^2 / 2 a_k                         (the command of step k + 1)
//     a_{k+1} = (-m a_g[k+1] - c (v_k + dt / 2 a_k) - (1 - alpha) k u_{k+1} - F_{k+1})
//               / (m + c dt / 2)                                    (F: the load cell's reading)
//     v_{k+1} = v_k + dt / 2 (a_k + a_{k+1})
//   Actuator: the declared 14 ms lag as a time shift of the command (linear between samples),
//   then the case's own effects (first-order lag, amplitude-dependent gain, pump ripple).
//   Specimen: force of the true rod displacement x (linear alpha k x unless the case says).
//   Sensors: displacement y = x (+ cubic calibration) + N(0, 2 um), 16-bit over +-50 mm;
//   load cell F = f (+ offset, drift, ripple) + N(0, 0.5 N), 16-bit over +-10 kN.
// Record step k holds t_k = k dt and the state at t_k: u_k, v_k, a_k, command u_k, realised y_k
// and force F_k; step 0 is the rest before the first exchange (nothing answered yet).

#include <google/protobuf/text_format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "blind_record.h"
#include "rths/proto/config.pb.h"
#include "rths/proto/deployment.pb.h"
#include "rths/proto/runtime.pb.h"

namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
using blind::Motion;
using blind::read_motion;

// ---------- the cases: effects, parameters and truths ----------

// What the rig does beside the declared 14 ms shift. Zero / false = absent.
struct Rig {
  double first_order_tau = 0.0;  // s, an extra first-order lag of the rod (library: first_order)
  double actuator_cubic = 0.0;   // 1/m^2, x = x_d (1 - c x_d^2): the rod falls short at amplitude
  double actuator_ripple_amp = 0.0;  // m, pump ripple on the rod position
  double actuator_ripple_hz = 0.0;
  double compression_ratio = 1.0;  // specimen stiffness for x < 0 over that for x >= 0
  double softening = 0.0;  // specimen stiffness falls linearly by this fraction over the run
  double quadratic_damping = 0.0;  // N s^2/m^2, f += c2 v |v| (an orifice)
  double sensor_cubic = 0.0;       // 1/m^2, y = x (1 + c y x^2): the transducer's calibration
  double cell_offset = 0.0;        // N, at t = 0 (library: offset_drift)
  double cell_drift = 0.0;         // N/s
  double cell_ripple_amp = 0.0;    // N, hydraulic ripple on the measured force
  double cell_ripple_hz = 0.0;
  double cell_thermal_amp = 0.0;  // N, a periodic temperature drift of the load cell's zero
  double cell_thermal_hz = 0.0;
};

struct Truth {
  std::string part;                // "" for a clean rig
  std::vector<std::string> kinds;  // unexplained description kinds that fit it
  double frequency_hz = 0.0;       // periodic only
  // Library effects (identify's docs) in the rig: {"part", "effect"}.
  std::vector<std::pair<std::string, std::string>> library;
  std::string what;  // for people
  // Names identify's docs give that describe the effect itself (not required, never wrong).
  std::vector<std::pair<std::string, std::string>> accepted = {};
};

struct Case {
  std::string name;
  std::string set;  // "tune" or "report"
  std::uint64_t seed;
  Rig rig;
  Truth truth;
};

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  auto add = [&](std::string set, std::string name, std::uint64_t seed, Rig rig, Truth truth) {
    cases.push_back(Case{std::move(name), std::move(set), seed, rig, std::move(truth)});
  };
  // The same families in both sets; parameters and seeds differ so that nothing tuned on `tune`
  // carries to `report` by coincidence of a frequency or a size.
  struct Params {
    std::string set;
    std::uint64_t seed;
    double tau, cell_offset, cell_drift, ripple_hz, ripple_n, thermal_hz, thermal_n;
    double act_ripple_hz, act_ripple_m, compression, softening, quad, sensor_cubic, act_cubic;
  };
  const Params sets[] = {
      {"tune", 1100, 0.008, 300.0, 15.0, 13.0, 60.0, 0.20, 80.0, 23.0, 0.25e-3, 1.5, 0.30, 3000.0,
       300.0, 300.0},
      {"report", 7700, 0.006, -250.0, 25.0, 19.0, 45.0, 0.13, 60.0, 9.5, 0.15e-3, 1.35, 0.22,
       2200.0, -250.0, 400.0},
  };
  for (const Params& p : sets) {
    const std::string s = p.set;
    std::uint64_t seed = p.seed;
    auto tag = [&](const char* name) { return s + "_" + name; };
    add(s, tag("clean"), seed++, Rig{}, Truth{"", {}, 0.0, {}, "noise and converters only"});
    {
      Rig r;
      r.first_order_tau = p.tau;
      std::ostringstream w;
      w << "an extra first-order lag of " << p.tau * 1e3 << " ms";
      add(s, tag("first_order"), seed++, r,
          Truth{"", {}, 0.0, {{"actuator 1", "first_order"}}, w.str()});
    }
    {
      Rig r;
      r.cell_offset = p.cell_offset;
      r.cell_drift = p.cell_drift;
      std::ostringstream w;
      w << "load cell offset " << p.cell_offset << " N and drift " << p.cell_drift << " N/s";
      add(s, tag("cell_offset_drift"), seed++, r,
          Truth{"", {}, 0.0, {{"load cell 1", "offset_drift"}}, w.str()});
    }
    {
      Rig r;
      r.cell_ripple_amp = p.ripple_n;
      r.cell_ripple_hz = p.ripple_hz;
      std::ostringstream w;
      w << "hydraulic pump ripple on the measured force, " << p.ripple_n << " N at " << p.ripple_hz
        << " Hz";
      add(s, tag("pump_ripple_force"), seed++, r,
          Truth{"load cell 1", {"periodic"}, p.ripple_hz, {}, w.str()});
    }
    {
      Rig r;
      r.cell_ripple_amp = p.ripple_n;
      r.cell_ripple_hz = p.ripple_hz * 1.1;
      r.first_order_tau = p.tau;
      std::ostringstream w;
      w << "pump ripple " << p.ripple_n << " N at " << p.ripple_hz * 1.1
        << " Hz on the force and an extra first-order lag of " << p.tau * 1e3 << " ms";
      add(s, tag("ripple_and_lag"), seed++, r,
          Truth{"load cell 1",
                {"periodic"},
                p.ripple_hz * 1.1,
                {{"actuator 1", "first_order"}},
                w.str()});
    }
    {
      Rig r;
      r.cell_thermal_amp = p.thermal_n;
      r.cell_thermal_hz = p.thermal_hz;
      std::ostringstream w;
      w << "periodic temperature drift of the load cell's zero, " << p.thermal_n << " N at "
        << p.thermal_hz << " Hz";
      add(s, tag("thermal_cycle_cell"), seed++, r,
          Truth{"load cell 1", {"periodic", "time_varying"}, p.thermal_hz, {}, w.str()});
    }
    {
      Rig r;
      r.actuator_ripple_amp = p.act_ripple_m;
      r.actuator_ripple_hz = p.act_ripple_hz;
      std::ostringstream w;
      w << "pump ripple on the rod position, " << p.act_ripple_m * 1e3 << " mm at "
        << p.act_ripple_hz << " Hz";
      add(s, tag("pump_ripple_rod"), seed++, r,
          Truth{"actuator 1", {"periodic"}, p.act_ripple_hz, {}, w.str()});
    }
    {
      Rig r;
      r.compression_ratio = p.compression;
      std::ostringstream w;
      w << "specimen " << p.compression << " x stiffer in compression (x < 0) than in tension";
      add(s, tag("compression_stiffer"), seed++, r,
          Truth{"specimen 1", {"direction"}, 0.0, {}, w.str()});
    }
    {
      Rig r;
      r.softening = p.softening;
      std::ostringstream w;
      w << "specimen softening by " << p.softening * 100 << " % over the run (damage)";
      // docs/identify.md: a time-varying stiffness is named, though no stage re-runs it.
      add(s, tag("softening"), seed++, r,
          Truth{"specimen 1",
                {"time_varying"},
                0.0,
                {},
                w.str(),
                {{"specimen 1", "time_varying_stiffness"}}});
    }
    {
      Rig r;
      r.quadratic_damping = p.quad;
      std::ostringstream w;
      w << "specimen force c2 v |v|, c2 = " << p.quad << " N s^2/m^2";
      add(s, tag("velocity_squared"), seed++, r,
          Truth{"specimen 1", {"amplitude"}, 0.0, {}, w.str()});
    }
    {
      Rig r;
      r.sensor_cubic = p.sensor_cubic;
      std::ostringstream w;
      w << "displacement transducer with a cubic calibration, y = x (1 + " << p.sensor_cubic
        << " x^2)";
      add(s, tag("cubic_transducer"), seed++, r,
          Truth{"displacement sensor 1", {"amplitude"}, 0.0, {}, w.str()});
    }
    {
      Rig r;
      r.actuator_cubic = p.act_cubic;
      std::ostringstream w;
      w << "actuator falling short at amplitude, x = x_d (1 - " << p.act_cubic << " x_d^2)";
      add(s, tag("actuator_shortfall"), seed++, r,
          Truth{"actuator 1", {"amplitude"}, 0.0, {}, w.str()});
    }
  }
  return cases;
}

// ---------- the closed loop ----------

struct Sample {
  double u, v, a, command, realised, force;
};

struct Frame {
  double m = 1000.0, period = 0.5, zeta = 0.05, alpha = 1.0 / 3.0, dt = 0.001, lag = 0.014;
  double omega() const { return 2.0 * kPi / period; }
  double k() const { return m * omega() * omega(); }
  double c() const { return 2.0 * zeta * omega() * m; }
};

double quantise(double value, double full_scale) {
  const double q = 2.0 * full_scale / 65536.0;
  const double clipped = std::clamp(value, -full_scale, full_scale - q);
  return std::round(clipped / q) * q;
}

std::vector<Sample> simulate(const Frame& f, const Rig& rig, const std::vector<double>& ag,
                             std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int n = static_cast<int>(ag.size());
  const double t_end = (n - 1) * f.dt;
  const int lag_steps = static_cast<int>(std::lround(f.lag / f.dt));
  std::vector<double> commands(n, 0.0);
  std::vector<Sample> out(n);
  double x_rod = 0.0, x_prev = 0.0;  // rod (true) position now and one step before
  double lagged_prev = 0.0;          // the first-order lag's input at the step before
  // The rig between the command of step k and the load cell's reading: returns {y, F}.
  auto rig_step = [&](int k) {
    const double t = k * f.dt;
    const double desired = k >= lag_steps ? commands[k - lag_steps] : 0.0;  // 14 ms shift
    double x = desired;
    if (rig.first_order_tau > 0.0) {
      // tau x' = r - x with r ramping linearly over the step from lagged_prev to desired.
      const double tau = rig.first_order_tau;
      const double slope = (desired - lagged_prev) / f.dt;
      const double e = std::exp(-f.dt / tau);
      x = desired - slope * tau + (x_rod - lagged_prev + slope * tau) * e;
      lagged_prev = desired;
    }
    // State of the lag (x_rod before the other effects) is kept separate from the rod's output.
    const double lag_state = x;
    if (rig.actuator_cubic != 0.0) x *= 1.0 - rig.actuator_cubic * x * x;
    if (rig.actuator_ripple_amp != 0.0)
      x += rig.actuator_ripple_amp * std::sin(2.0 * kPi * rig.actuator_ripple_hz * t + 0.4);
    const double velocity = (x - x_prev) / f.dt;
    x_prev = x;
    x_rod = lag_state;
    // Specimen.
    double k_s = f.alpha * f.k() * (1.0 - rig.softening * t / t_end);
    if (x < 0.0) k_s *= rig.compression_ratio;
    double force = k_s * x + rig.quadratic_damping * velocity * std::abs(velocity);
    // Sensors.
    const double y = x * (1.0 + rig.sensor_cubic * x * x) + 2e-6 * unit(rng);
    force += rig.cell_offset + rig.cell_drift * t;
    force += rig.cell_ripple_amp * std::sin(2.0 * kPi * rig.cell_ripple_hz * t + 1.1);
    force += rig.cell_thermal_amp * std::sin(2.0 * kPi * rig.cell_thermal_hz * t);
    force += 0.5 * unit(rng);
    return std::pair{quantise(y, 0.05), quantise(force, 10000.0)};
  };
  const double kn = (1.0 - f.alpha) * f.k(), c = f.c(), m = f.m, dt = f.dt;
  auto [y0, force0] = rig_step(0);
  double u = 0.0, v = 0.0;
  double a = (-m * ag[0] - force0) / (m + c * dt / 2.0);
  out[0] = {u, v, a, 0.0, y0, force0};
  for (int k = 1; k < n; ++k) {
    const double u_next = u + dt * v + dt * dt / 2.0 * a;
    commands[k] = u_next;
    auto [y, force] = rig_step(k);
    const double a_next =
        (-m * ag[k] - c * (v + dt / 2.0 * a) - kn * u_next - force) / (m + c * dt / 2.0);
    v += dt / 2.0 * (a + a_next);
    u = u_next;
    a = a_next;
    out[k] = {u, v, a, u, y, force};
  }
  return out;
}

// ---------- the record and truth.json (blind_record.h) ----------

void write_record(const fs::path& path, const Case& c, const Frame& f, const Motion& motion,
                  double duration) {
  const std::vector<Sample> run = simulate(f, c.rig, motion.accel, c.seed);
  blind::RunToRecord to_record{"blind-" + c.name, c.seed, f.dt, duration, &motion, {}};
  for (const Sample& r : run)
    to_record.steps.push_back({r.u, r.v, r.a, r.command, r.realised, r.force});
  blind::write_run_record(path, to_record);
}

void write_truth(const fs::path& path, const std::vector<Case>& cases, double duration) {
  std::vector<blind::TruthCase> truths;
  for (const Case& c : cases)
    truths.push_back({c.name,
                      c.set,
                      c.seed,
                      c.truth.what,
                      c.truth.part,
                      {c.truth.kinds.begin(), c.truth.kinds.end()},
                      c.truth.frequency_hz,
                      {c.truth.library.begin(), c.truth.library.end()},
                      {c.truth.accepted.begin(), c.truth.accepted.end()},
                      std::nullopt});
  blind::write_truth(path, truths, duration);
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<blind::WriterArgs> args =
      blind::writer_args(argc, argv, "blind_record_writer", {"tune", "report"});
  if (!args) return 2;
  const std::string &set = args->set, &out_dir = args->out_dir, &data_dir = args->data_dir,
                    &only = args->only;
  const double duration = args->duration;
  try {
    const Frame f;
    const int steps = static_cast<int>(std::lround(duration / f.dt));
    const Motion motion = read_motion(data_dir, f.dt, steps);
    std::vector<Case> chosen;
    for (const Case& c : all_cases())
      if (c.set == set && (only.empty() || c.name == only)) chosen.push_back(c);
    if (chosen.empty()) throw std::runtime_error("no case " + only + " in set " + set);
    fs::create_directories(out_dir);
    for (const Case& c : chosen) {
      write_record(fs::path(out_dir) / (c.name + ".rthsrec"), c, f, motion, duration);
      std::cout << "wrote " << (fs::path(out_dir) / (c.name + ".rthsrec")).string() << ": "
                << c.truth.what << "\n";
    }
    write_truth(fs::path(out_dir) / "truth.json", chosen, duration);
  } catch (const std::exception& e) {
    std::cerr << "blind_record_writer: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
