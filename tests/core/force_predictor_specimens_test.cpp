// The force predictor (core/force_predictor.h) against specimens whose form it does not share
// (issue 61): a damper (a spring and a dashpot, the dashpot declared as the experimental DOF's
// damping) behind an actuator with its own lag and a load cell with its own, across a 60 ms
// round trip whose answers arrive with jitter, out of order, or never. Two checks:
//   - open loop: a known drift history through that rig and link, the predictor's force against
//     the lag-free specimen's at the command, its fitted k and c, and its windowed error;
//   - closed loop (core::simulate with the answers replayed as the link delivered them): a
//     3-storey frame with the damper (or a spring losing stiffness through the test) in storey 2,
//     the predictor started 30 % soft; E_rms of every floor against the lag-free reference, with
//     the shipped bound (50 %) in force, across 60 and 100 ms round trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/answer_replay.h"
#include "core/delay.h"
#include "core/force_predictor.h"
#include "core/ground_motion.h"
#include "core/metrics.h"
#include "core/rig_effects.h"
#include "core/simulation.h"
#include "core/structure.h"
#include "core/substructure.h"
#include "study/motion_files.h"

namespace rths::core {
namespace {

constexpr double kDt = 1e-3;            // s, the integrator's step
constexpr double kRoundTrip = 0.060;    // s, 30 ms each way (the far case: 100 ms)
constexpr double kJitterSd = 0.0025;    // s, each way
constexpr double kLoss = 0.01;          // of answers lost
constexpr double kActuatorLag = 0.010;  // s, first-order time constant
constexpr double kLoadCellLag = 0.003;  // s, the force channel's own lag
constexpr double kDamperK = 3.0e5;      // N/m
constexpr double kDamperC = 1.0e4;      // N s/m

// The damper as a study declares it (experimental DOF with a damping): a spring with a dashpot
// whose rate is the backward difference over the servo period.
std::unique_ptr<RestoringForceModel> damper() {
  return std::make_unique<InertialSpecimen>(std::make_unique<LinearSpring>(kDamperK), 0.0, kDamperC,
                                            kDt);
}

// The rig between the command and what the lab reads: the actuator's lag, then the load cell's.
DelayChain rig(double load_cell_lag = kLoadCellLag) {
  DelayChain chain;
  chain.add(std::make_unique<FirstOrderActuator>(kActuatorLag, kDt));
  chain.add(std::make_unique<ForceDelay>(load_cell_lag, kDt));
  return chain;
}

// The link's messages: the answer to step j arrives round_trip plus one N(0, kJitterSd) draw each
// way after step j (at least one step), a fraction kLoss never; at step k the loop uses the
// newest answer arrived (0: none yet), as the coordinator's intake does. Seeded, deterministic.
std::vector<std::int64_t> link_schedule(std::size_t steps, std::uint64_t seed,
                                        double round_trip = kRoundTrip) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> jitter(0.0, kJitterSd);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<std::int64_t> used(steps, 0);
  for (std::size_t j = 1; j < steps; ++j) {
    const double late = std::max(round_trip + jitter(random) + jitter(random), kDt);
    if (uniform(random) < kLoss) continue;
    const auto at = j + static_cast<std::size_t>(std::ceil(late / kDt - 1e-9));
    if (at < steps) used[at] = std::max(used[at], static_cast<std::int64_t>(j));
  }
  for (std::size_t k = 1; k < steps; ++k) used[k] = std::max(used[k], used[k - 1]);
  return used;
}

PredictorParameters started_30_percent_soft() {
  PredictorParameters p;
  p.stiffness = 0.7 * kDamperK;
  p.max_relative_error = 0.5;  // the shipped configs' bound
  return p;
}

double drift(double t) {
  const double w = 4 * std::numbers::pi;
  return 0.01 * std::sin(w * t) + 0.004 * std::sin(2.7 * w * t);
}

struct OpenLoop {
  double force_error = 0.0;  // RMS (force - lag-free force) / RMS lag-free force, t >= 3 s
  PredictorOutput last;
};

// The drift history through the rig and the link into a predictor with the damper's shape.
OpenLoop open_loop(ForcePredictor& predictor, std::size_t steps,
                   double load_cell_lag = kLoadCellLag) {
  Actuator rig_actuator(rig(load_cell_lag), damper());
  rig_actuator.set_servo(1, kDt);
  auto lag_free = damper();
  const std::vector<std::int64_t> used = link_schedule(steps, 61);
  std::vector<double> realised(steps, 0.0), force(steps, 0.0);
  double error = 0.0, truth = 0.0;
  OpenLoop out;
  for (std::size_t k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * kDt, u = drift(t);
    const double v = (u - drift(t - kDt)) / kDt;
    const ActuatorOutput measured = rig_actuator.step({t, u, v});
    realised[k] = measured.realised;
    force[k] = measured.force;
    PredictorInput in{u, v, used[k] > 0 ? static_cast<long>(used[k]) : -1, 0.0, 0.0};
    if (in.answer_step >= 0) {
      in.measured_displacement = realised[static_cast<std::size_t>(used[k])];
      in.measured_force = force[static_cast<std::size_t>(used[k])];
    }
    out.last = predictor.step(in);
    const double f = lag_free->step(u);
    if (t >= 3.0) {
      error += (out.last.force - f) * (out.last.force - f);
      truth += f * f;
    }
  }
  out.force_error = std::sqrt(error / truth);
  return out;
}

TEST(ForcePredictorSpecimens, ADamperBehindALaggingRigAndAJitteredLinkIsFittedWithItsDashpot) {
  ForcePredictor predictor(started_30_percent_soft(), kDt, "damper", damper().get());
  const OpenLoop run = open_loop(predictor, 8000);
  // The load cell's 3 ms is the model's lag term T (first order: a pure delay reads somewhat
  // short), so c is the dashpot's, not c - k 3 ms; the link's span differences cost O(dt).
  EXPECT_NEAR(run.last.stiffness, kDamperK, 0.02 * kDamperK);
  EXPECT_NEAR(run.last.damping, kDamperC, 0.05 * kDamperC);
  EXPECT_GT(run.last.force_lag, 0.001);
  EXPECT_LT(run.last.force_lag, 0.004);
  EXPECT_LT(run.last.relative_error, 0.05);
  EXPECT_FALSE(run.last.exceeded);
  // Each fitted term carries its standard error, positive and below the term.
  const PredictorTerms error = predictor.uncertainty();
  EXPECT_GT(error.stiffness, 0.0);
  EXPECT_LT(error.stiffness, 0.05 * run.last.stiffness);
  EXPECT_GT(error.force_lag, 0.0);
  EXPECT_LT(error.force_lag, run.last.force_lag);
  // What is left is the lag's second order and the correction's 60 ms age.
  EXPECT_LT(run.force_error, 0.04)
      << predictor.model_text() << ", relative error " << run.last.relative_error;
}

TEST(ForcePredictorSpecimens, ADeclaredDashpotIsTheModelsDampingNotPartOfItsShape) {
  // Started where the declaration is, scaled as the stiffness is (30 % soft: c 0.7 c_s) ...
  ForcePredictor soft(started_30_percent_soft(), kDt, "damper", damper().get());
  EXPECT_NEAR(soft.damping(), 0.7 * kDamperC, 1e-9 * kDamperC);
  // ... unless the predictor's damping is given.
  PredictorParameters given = started_30_percent_soft();
  given.damping = 500.0;
  EXPECT_EQ(ForcePredictor(given, kDt, "damper", damper().get()).damping(), 500.0);
  // The shape is the spring alone: the rate is the integrator's v, not a difference of calls.
  PredictorInput in;
  in.command = 0.01;
  in.command_velocity = 0.2;
  EXPECT_NEAR(soft.step(in).predicted, 0.7 * (kDamperK * 0.01 + kDamperC * 0.2), 1e-9 * kDamperK);
}

TEST(ForcePredictorSpecimens, AForceLaggingPastTheDashpotIsNamedAsTheMissingLagBeforeTheHold) {
  // 50 ms on the load cell: the force lags its drift as a dashpot of 1e4 - 3e5 x 0.05 = -5e3 N s/m
  // would lead. A first-order lag term cannot follow 50 ms (0.86 rad at the motion's RMS rate):
  // the fit with it still leaves more than 5 %, so it is held at 0, the best c is negative and
  // held at 0; the bound (5 % here) trips and its reason names the lag, not only the figure.
  PredictorParameters p = started_30_percent_soft();
  p.max_relative_error = 0.05;
  ForcePredictor predictor(p, kDt, "damper", damper().get());
  const OpenLoop run = open_loop(predictor, 8000, 0.050);
  EXPECT_TRUE(run.last.exceeded);
  EXPECT_EQ(run.last.damping, 0.0);
  EXPECT_EQ(run.last.force_lag, 0.0);
  EXPECT_LT(predictor.free_damping(), -0.5 * (kDamperK * 0.050 - kDamperC));
  const std::string reason = predictor.rejection();
  EXPECT_NE(reason.find("the measured force lags the measured drift by at least"),
            std::string::npos)
      << reason;
  EXPECT_NE(reason.find("the model lacks the force channel's lag"), std::string::npos) << reason;
  EXPECT_NE(reason.find("lacks the force's lag"), std::string::npos) << reason;
  // The 3 ms rig of the test above: the fit needs no c = 0 rule and names nothing.
  ForcePredictor within(started_30_percent_soft(), kDt, "damper", damper().get());
  open_loop(within, 8000);
  EXPECT_GT(within.free_damping(), 0.0);
  EXPECT_EQ(within.rejection(), "");
}

// A spring whose stiffness drifts: k = k0 (1 - rate t), t counted in calls h apart (a specimen
// that degrades through the test, which no fixed model holds).
class DriftingSpring final : public RestoringForceModel {
 public:
  DriftingSpring(double k0, double rate, double h) : k0_(k0), rate_(rate), h_(h) {}
  ForceState trial(double drift) override {
    const double k = k0_ * (1.0 - rate_ * static_cast<double>(calls_) * h_);
    return {k * drift, k};
  }
  void commit() override { ++calls_; }
  void reset() override { calls_ = 0; }
  double initial_stiffness() const override { return k0_; }
  std::unique_ptr<RestoringForceModel> clone() const override {
    return std::make_unique<DriftingSpring>(*this);
  }
  std::string describe() const override { return "drifting spring"; }

 private:
  double k0_, rate_, h_;
  long calls_ = 0;
};

// A 3-storey frame: `mass` kg a floor, `columns` N/m a storey, 5 % Rayleigh on the storeys'
// stiffness with `specimen_stiffness` (N/m) added in storey 2.
struct Frame {
  double mass = 1000.0, columns = 8e5, specimen_stiffness = kDamperK;
};

// The frame with `specimen` in storey 2 beside its columns, shaken by 12 s of the Imperial Valley
// record the shipped studies use.
HybridSetup frame_with(const RestoringForceModel& specimen, const Frame& frame = {}) {
  HybridSetup setup;
  const double m = frame.mass, k = frame.columns;
  setup.model = make_shear_building({m, m, m}, {k, k + frame.specimen_stiffness, k});
  setup.model.damping = rayleigh_damping(setup.model.mass, setup.model.stiffness, 0.05);
  setup.dt = kDt;
  for (int s = 0; s < 3; ++s) {
    setup.partition.numerical.push_back(std::make_unique<LinearSpring>(k));
    setup.partition.experimental.push_back(s == 1 ? specimen.clone() : nullptr);
  }
  setup.partition.actuator_storeys = {1};
  return setup;
}

GroundMotion imperial_valley(double seconds) {
  return truncated(
      resampled(study::read_at2(RTHS_DATA_DIR "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2"),
                kDt),
      seconds);
}

// E_rms and E_peak (%) of the worst floor against the reference, over the steps both ran.
struct FloorErrors {
  double rms = 0.0, peak = 0.0;
};
FloorErrors worst_floor_errors_pct(const SimulationResult& run, const SimulationResult& reference) {
  FloorErrors worst;
  const auto steps = static_cast<Eigen::Index>(std::min(run.steps(), reference.steps()));
  for (Eigen::Index f = 0; f < reference.displacement.cols(); ++f) {
    const Vec r = reference.displacement.col(f).head(steps),
              x = run.displacement.col(f).head(steps);
    const std::vector<double> expected(r.begin(), r.end()), got(x.begin(), x.end());
    worst.rms = std::max(worst.rms, relative_rms_error_pct(expected, got));
    worst.peak = std::max(worst.peak, relative_peak_error_pct(expected, got));
  }
  return worst;
}

// The frame with `specimen` behind the rig and the jittered link (`round_trip`), uncompensated
// and with `predictor` (the shipped bound in force): E_rms and E_peak (%) of the worst floor
// against the lag-free reference (1e9 when the run did not complete), and the HOLD's reason.
struct FrameRuns {
  double uncompensated = 0.0, predicted = 0.0, predicted_peak = 0.0;
  std::string held;
};
FrameRuns frame_runs(const RestoringForceModel& specimen, const PredictorParameters& predictor,
                     double round_trip = kRoundTrip, const Frame& frame = {}) {
  const GroundMotion motion = imperial_valley(12.0);
  const SimulationResult reference = simulate(frame_with(specimen, frame), motion);
  AnswerSchedule link;
  link.actuator_used = {link_schedule(motion.acceleration.size(), 2026, round_trip)};
  SimulationOptions options;
  options.divergence_bound = 1.0;
  const auto errors = [&reference](const SimulationResult& run) {
    return run.diverged || run.steps() < reference.steps() ? FloorErrors{1e9, 1e9}
                                                           : worst_floor_errors_pct(run, reference);
  };
  HybridSetup setup = frame_with(specimen, frame);
  setup.delays.push_back(rig());
  FrameRuns out;
  out.uncompensated = errors(simulate(setup, motion, options, link)).rms;
  setup.predictors = {predictor};
  const SimulationResult run = simulate(setup, motion, options, link);
  const FloorErrors predicted = errors(run);
  out.predicted = predicted.rms;
  out.predicted_peak = predicted.peak;
  out.held = run.held;
  std::cout << specimen.describe() << " across " << 1e3 * round_trip << " ms: E_rms uncompensated "
            << out.uncompensated << " %, predicted E_rms " << out.predicted << " %, E_peak "
            << out.predicted_peak << " %" << std::endl;
  return out;
}

TEST(ForcePredictorSpecimens, AFrameWithTheDamperAcrossJittered60And100MsLinksMatchesItsReference) {
  const FrameRuns runs = frame_runs(*damper(), started_30_percent_soft());

  // Without the predictor the round trip is far past the loop's critical delay.
  EXPECT_GT(runs.uncompensated, 50.0);
  EXPECT_TRUE(runs.held.empty()) << runs.held;
  EXPECT_LE(runs.predicted, 5.0);
  // The far case: a 100 ms round trip, the same rig and jitter.
  const FrameRuns far = frame_runs(*damper(), started_30_percent_soft(), 0.100);
  EXPECT_GT(far.uncompensated, 50.0);
  EXPECT_TRUE(far.held.empty()) << far.held;
  EXPECT_LE(far.predicted, 5.0);
}

TEST(ForcePredictorSpecimens, AFrameWhoseSpecimenLosesStiffnessThroughTheTestMatchesItsReference) {
  // Stiffness lost at 2 % a second (24 % by the end). The lab declares the specimen as it was (a
  // line: specimen_shape false), the drift being what no declaration knows; the fit follows it.
  PredictorParameters line = started_30_percent_soft();
  line.specimen_shape = false;
  const FrameRuns drifting = frame_runs(DriftingSpring(kDamperK, 0.02, kDt), line);
  EXPECT_GT(drifting.uncompensated, 50.0);
  EXPECT_TRUE(drifting.held.empty()) << drifting.held;
  EXPECT_LE(drifting.predicted, 5.0);
}

// The MR damper of data/measured (mts_mrdamper_chirp_0A.txt at 0 A) as rths identify fits it
// (`rths identify data/measured/mts_mrdamper_chirp_0A.txt --channels force`, kind mr_damper plus
// Coulomb friction, held-out 27.8 %): f = c v + F_c tanh(v / v_c) + F_bw z, z Bouc-Wen (n 1,
// beta = gamma) of yield drift d_y; v the backward difference over calls h apart (the servo
// period). Its friction is a term the predictor's model does not have.
constexpr double kMrDamping = 1778.6;      // N s/m, c
constexpr double kMrHysteretic = 91.32;    // N, F_bw
constexpr double kMrYield = 4.769e-5;      // m, d_y
constexpr double kMrFriction = 64.93;      // N, F_c
constexpr double kMrSmoothing = 6.566e-3;  // m/s, v_c

class MrDamper final : public RestoringForceModel {
 public:
  explicit MrDamper(double h) : h_(h), z_(kMrHysteretic / kMrYield, kMrYield, 0.0, 1.0, 0.5) {}
  ForceState trial(double drift) override {
    trial_ = drift;
    const double v = (drift - x1_) / h_, slope = std::tanh(v / kMrSmoothing);
    const ForceState hysteresis = z_.trial(drift);
    return {
        kMrDamping * v + kMrFriction * slope + hysteresis.force,
        hysteresis.tangent + (kMrDamping + kMrFriction * (1 - slope * slope) / kMrSmoothing) / h_};
  }
  void commit() override {
    z_.commit();
    x1_ = trial_;
  }
  void reset() override {
    z_.reset();
    x1_ = trial_ = 0.0;
  }
  double initial_stiffness() const override { return z_.initial_stiffness(); }
  std::unique_ptr<RestoringForceModel> clone() const override {
    return std::make_unique<MrDamper>(*this);
  }
  std::string describe() const override { return "MR damper (identified, with friction)"; }

 private:
  double h_;
  BoucWen z_;
  double x1_ = 0.0, trial_ = 0.0;
};

// The damper as identify's fragment declares it (its Bouc-Wen; its dashpot as the predictor's
// damping), the model 30 % off in every term. The damper yields at 0.05 mm: the fit is trusted
// from 0.01 mm of RMS drift (the default 0.1 mm never starts it in this frame, and the bound
// HOLDs the run at 2 s).
PredictorParameters mr_damper_predictor() {
  PredictorParameters p;
  p.shape = std::make_shared<BoucWen>(kMrHysteretic / kMrYield, kMrYield, 0.0, 1.0, 0.5);
  p.stiffness = 0.7 * kMrHysteretic / kMrYield;
  p.damping = 0.7 * kMrDamping;
  p.max_relative_error = 0.5;
  p.min_displacement = 1e-5;
  return p;
}

// A laboratory-scale frame the damper's hundreds of newtons move: 100 kg a floor, 5e4 N/m a
// storey (peak drift 17 mm under the record); uncompensated, the delayed dashpot diverges it.
constexpr Frame kSmallFrame{100.0, 5e4, 0.0};

// The target at 60 ms (E_rms <= 5 %). What is left is the friction, which the model
// does not have: without it (identify's mr_damper kind alone) the same runs read 0.40 % and
// 0.55 %. At 100 ms the stale correction of the friction costs more (6.6 % measured).
TEST(ForcePredictorSpecimens, TheIdentifiedMrDamperAcross60And100MsMatchesItsReference) {
  const FrameRuns near = frame_runs(MrDamper(kDt), mr_damper_predictor(), 0.060, kSmallFrame);
  EXPECT_GT(near.uncompensated, 100.0);
  EXPECT_TRUE(near.held.empty()) << near.held;
  EXPECT_LE(near.predicted, 5.0);
  const FrameRuns far = frame_runs(MrDamper(kDt), mr_damper_predictor(), 0.100, kSmallFrame);
  EXPECT_GT(far.uncompensated, 100.0);
  EXPECT_TRUE(far.held.empty()) << far.held;
  EXPECT_LE(far.predicted, 8.0);
}

// A column that yields sharply (bilinear, 2 % post-yield, at 2 mm of the 14 mm the frame
// reaches) where the lab declared a smooth one (Bouc-Wen n 1 of the same yield drift and ratio):
// the model's hysteresis is not the specimen's. Fitted as a line instead (no h term: what the
// predictor held before it had one), the same column reads 8.2 % at 60 ms.
TEST(ForcePredictorSpecimens, ASharplyYieldingColumnDeclaredSmoothMatchesItsReference) {
  constexpr double kYield = 0.002, kRatio = 0.02;
  const BilinearKinematic column(kDamperK, kYield, kRatio);
  PredictorParameters smooth = started_30_percent_soft();
  smooth.shape = std::make_shared<BoucWen>(kDamperK, kYield, kRatio, 1.0, 0.5);
  const FrameRuns near = frame_runs(column, smooth);
  EXPECT_GT(near.uncompensated, 30.0);
  EXPECT_TRUE(near.held.empty()) << near.held;
  EXPECT_LE(near.predicted, 5.0);
  const FrameRuns far = frame_runs(column, smooth, 0.100);  // 5.2 % measured
  EXPECT_TRUE(far.held.empty()) << far.held;
  EXPECT_LE(far.predicted, 6.0);
  PredictorParameters line = started_30_percent_soft();
  line.specimen_shape = false;
  EXPECT_GT(frame_runs(column, line).predicted, 5.0);
}

// The drifting specimen of the test above across the far round trip.
TEST(ForcePredictorSpecimens, AFrameWhoseSpecimenLosesStiffnessAcross100MsMatchesItsReference) {
  PredictorParameters line = started_30_percent_soft();
  line.specimen_shape = false;
  const FrameRuns drifting = frame_runs(DriftingSpring(kDamperK, 0.02, kDt), line, 0.100);
  EXPECT_GT(drifting.uncompensated, 50.0);
  EXPECT_TRUE(drifting.held.empty()) << drifting.held;
  EXPECT_LE(drifting.predicted, 5.0);
}

}  // namespace
}  // namespace rths::core
