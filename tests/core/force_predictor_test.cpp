#include "core/force_predictor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace rths::core {
namespace {

constexpr double kDt = 1e-3;
constexpr double kOmega = 4 * std::numbers::pi;  // rad/s, the paper frame's 2 Hz

double drift(double t) { return 0.01 * std::sin(kOmega * t) + 0.004 * std::sin(2.7 * kOmega * t); }
double drift_rate(double t) {
  return 0.01 * kOmega * std::cos(kOmega * t) + 0.004 * 2.7 * kOmega * std::cos(2.7 * kOmega * t);
}

// A remote linear specimen k_e, c_e answering `lag` steps late: the answer the coordinator holds
// at step k describes step k - lag (its sensor's drift and the force it measured there).
struct RemoteLink {
  double k_e, c_e;
  long lag;
  PredictorInput at(long k) const {
    PredictorInput in;
    const double t = static_cast<double>(k) * kDt;
    in.command = drift(t);
    in.command_velocity = drift_rate(t);
    in.answer_step = k - lag;
    if (in.answer_step >= 0) {
      const double t_m = static_cast<double>(in.answer_step) * kDt;
      in.measured_displacement = drift(t_m);
      in.measured_force = k_e * drift(t_m) + c_e * drift_rate(t_m);
    }
    return in;
  }
};

PredictorParameters declared(double k, double c = 0.0) {
  PredictorParameters p;
  p.stiffness = k;
  p.damping = c;
  return p;
}

TEST(ForcePredictor, RightModelHidesTheLagWhollyAndBeforeTheFirstAnswerUsesTheModel) {
  const double k = 5.0e4;
  ForcePredictor predictor(declared(k), kDt);
  const RemoteLink link{k, 0.0, 74};
  for (long step = 0; step < 3000; ++step) {
    const PredictorInput in = link.at(step);
    const PredictorOutput out = predictor.step(in);
    // The lag-free force of the specimen at this step's command, to rounding (the fit may move
    // k by rounding once excited, never the force by more than 1e-9 of it).
    EXPECT_NEAR(out.force, k * in.command, 1e-9 * k * 0.014) << "step " << step;
    if (step < link.lag) EXPECT_EQ(out.error, 0.0);
  }
}

TEST(ForcePredictor, FixedWrongModelCarriesItsErrorAtTheOldStep) {
  const double k_e = 5.0e4, k_model = 0.7 * k_e;
  PredictorParameters p = declared(k_model);
  p.adapt = false;
  ForcePredictor predictor(p, kDt);
  const RemoteLink link{k_e, 0.0, 60};
  for (long step = 0; step < 500; ++step) {
    const PredictorInput in = link.at(step);
    const PredictorOutput out = predictor.step(in);
    const double expected_error = in.answer_step < 0 ? 0.0 : 0.3 * k_e * in.measured_displacement;
    EXPECT_NEAR(out.error, expected_error, 1e-9 * k_e);
    EXPECT_NEAR(out.force, k_model * in.command + expected_error, 1e-9 * k_e);
    EXPECT_EQ(out.stiffness, k_model);
  }
  EXPECT_EQ(predictor.updates(), 0u);
}

TEST(ForcePredictor, OnlineFitCorrectsAThirtyPercentStiffnessErrorAndFindsTheDamping) {
  const double k_e = 5.0e4, c_e = 300.0;
  PredictorParameters p = declared(0.7 * k_e);
  p.forgetting_time = 0.5;
  ForcePredictor predictor(p, kDt);
  const RemoteLink link{k_e, c_e, 60};
  PredictorOutput out;
  for (long step = 0; step < 5000; ++step) out = predictor.step(link.at(step));
  // The backward-difference velocity of the measured drift is half a step late: O(dt) in c.
  EXPECT_NEAR(out.stiffness, k_e, 1e-3 * k_e);
  EXPECT_NEAR(out.damping, c_e, 0.02 * c_e);
  EXPECT_GT(predictor.updates(), 4000u);
  const PredictorInput in = link.at(5000);
  out = predictor.step(in);
  EXPECT_NEAR(out.force, k_e * in.command + c_e * in.command_velocity, 2e-3 * k_e * 0.014);
}

TEST(ForcePredictor, NoFitOnARestingOrUnexcitedLinkNorWithNegativeStiffness) {
  ForcePredictor predictor(declared(4.0e4), kDt);
  PredictorInput in;
  for (long step = 0; step < 200; ++step) {
    in.answer_step = step;
    in.measured_displacement = 1e-6 * std::sin(kOmega * step * kDt);  // below 0.1 mm RMS
    in.measured_force = 9.0e4 * in.measured_displacement;
    predictor.step(in);
  }
  EXPECT_EQ(predictor.updates(), 0u);
  EXPECT_EQ(predictor.stiffness(), 4.0e4);
  ForcePredictor pushed(declared(4.0e4), kDt);
  for (long step = 0; step < 500; ++step) {
    in.answer_step = step;
    in.measured_displacement = drift(step * kDt);
    in.measured_force = -1.0e4 * in.measured_displacement;  // a specimen that pushes: refused
    pushed.step(in);
  }
  EXPECT_EQ(pushed.updates(), 0u);
  EXPECT_EQ(pushed.stiffness(), 4.0e4);
}

TEST(ForcePredictor, LostAnswersHoldTheLastPairAndABurstDifferencesOverItsSteps) {
  const double k = 2.0e4, c = 100.0;
  PredictorParameters p = declared(k, c);
  p.adapt = false;
  ForcePredictor predictor(p, kDt);
  PredictorInput in;
  in.answer_step = 10;
  in.measured_displacement = 0.001;
  in.measured_force = 25.0;
  PredictorOutput out = predictor.step(in);  // first answer: v_m = 0
  EXPECT_DOUBLE_EQ(out.error, 25.0 - k * 0.001);
  // The same answer again (a lost or late one): the error stays, the command moves.
  in.command = 0.002;
  out = predictor.step(in);
  EXPECT_DOUBLE_EQ(out.error, 25.0 - k * 0.001);
  EXPECT_DOUBLE_EQ(out.force, k * 0.002 + out.error);
  // An answer three steps on: its drift rate is over the three steps it spans.
  in.answer_step = 13;
  in.measured_displacement = 0.004;
  in.measured_force = 90.0;
  out = predictor.step(in);
  EXPECT_DOUBLE_EQ(out.error, 90.0 - (k * 0.004 + c * (0.003 / (3 * kDt))));
  // An older answer arriving after a newer one is ignored.
  in.answer_step = 12;
  in.measured_force = 1.0e6;
  EXPECT_DOUBLE_EQ(predictor.step(in).error, out.error);
}

TEST(ForcePredictor, RelativeErrorIsWindowedAndTheBoundTrips) {
  const double k_e = 5.0e4;
  PredictorParameters p = declared(0.5 * k_e);
  p.adapt = false;
  p.error_window = 0.1;
  p.max_relative_error = 0.4;
  ForcePredictor predictor(p, kDt);
  const RemoteLink link{k_e, 0.0, 5};
  PredictorOutput out;
  for (long step = 0; step < 104; ++step) {
    out = predictor.step(link.at(step));
    EXPECT_EQ(out.relative_error, 0.0) << "the window is not full before step 104";
  }
  out = predictor.step(link.at(104));
  EXPECT_NEAR(out.relative_error, 0.5, 1e-12);  // e = 0.5 f_m at every entry
  EXPECT_TRUE(out.exceeded);
  p.max_relative_error = 0.6;
  ForcePredictor within(p, kDt);
  for (long step = 0; step < 300; ++step) EXPECT_FALSE(within.step(link.at(step)).exceeded);
}

TEST(ForcePredictor, ResetReturnsToTheDeclaredModel) {
  const RemoteLink link{5.0e4, 0.0, 20};
  ForcePredictor predictor(declared(3.0e4), kDt);
  for (long step = 0; step < 2000; ++step) predictor.step(link.at(step));
  EXPECT_GT(predictor.stiffness(), 4.9e4);
  predictor.reset();
  EXPECT_EQ(predictor.stiffness(), 3.0e4);
  EXPECT_EQ(predictor.updates(), 0u);
  EXPECT_EQ(predictor.step(link.at(0)).error, 0.0);
}

TEST(ForcePredictor, RefusesParametersOutOfRangeNamingThem) {
  const auto message = [](PredictorParameters p, double dt = kDt) {
    try {
      ForcePredictor predictor(p, dt, "cases[1].force_predictor");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  PredictorParameters p = declared(1.0e4);
  EXPECT_EQ(message(p), "accepted");
  EXPECT_NE(message(declared(0.0)).find("cases[1].force_predictor: stiffness"), std::string::npos);
  PredictorParameters bad = p;
  bad.damping = -1.0;
  EXPECT_NE(message(bad).find("damping"), std::string::npos);
  bad = p;
  bad.forgetting_time = 0.0;
  EXPECT_NE(message(bad).find("forgetting_time"), std::string::npos);
  bad = p;
  bad.error_window = 0.5 * kDt;
  EXPECT_NE(message(bad).find("error_window"), std::string::npos);
  bad = p;
  bad.max_relative_error = -0.1;
  EXPECT_NE(message(bad).find("max_relative_error"), std::string::npos);
  bad = p;
  bad.min_displacement = std::nan("");
  EXPECT_NE(message(bad).find("min_displacement"), std::string::npos);
  EXPECT_NE(message(p, 0.0).find("dt"), std::string::npos);
}

TEST(ForcePredictor, ADeclaredHystereticSpecimenIsPredictedAlongTheCommandsOwnPath) {
  // A Bouc-Wen specimen answering 74 steps late, yielding (peak drift 1.75 x its yield drift):
  // with its own shape the model's error is the shape's rounding only, with an equivalent linear
  // model it is the hysteresis the line cannot follow.
  const double k = 5.0e4;
  const BoucWen specimen(k, 0.008, 0.1, 1.0, 0.5);
  const PredictorParameters p = declared(k);
  ForcePredictor shaped(p, kDt, "shaped", &specimen);
  PredictorParameters linear = p;
  linear.specimen_shape = false;
  ForcePredictor equivalent(linear, kDt, "equivalent", &specimen);
  auto remote = specimen.clone();
  auto lag_free = specimen.clone();
  std::vector<double> measured_force, measured_drift;
  double shaped_worst = 0.0, linear_worst = 0.0, peak = 0.0;
  for (long step = 0; step < 4000; ++step) {
    const double t = static_cast<double>(step) * kDt;
    const double u = 0.75 * drift(t) + 0.004 * std::sin(0.3 * kOmega * t);
    measured_drift.push_back(u);
    measured_force.push_back(remote->step(u));
    PredictorInput in;
    in.command = u;
    in.answer_step = step - 74;
    if (in.answer_step >= 0) {
      in.measured_displacement = measured_drift[static_cast<std::size_t>(in.answer_step)];
      in.measured_force = measured_force[static_cast<std::size_t>(in.answer_step)];
    }
    const double truth = lag_free->step(u);
    peak = std::max(peak, std::abs(truth));
    shaped_worst = std::max(shaped_worst, std::abs(shaped.step(in).force - truth));
    linear_worst = std::max(linear_worst, std::abs(equivalent.step(in).force - truth));
  }
  EXPECT_LT(shaped_worst, 1e-6 * peak);
  EXPECT_GT(linear_worst, 0.05 * peak);
  // A copy carries its own shapes: stepping it leaves the original where it was.
  ForcePredictor copy(shaped);
  PredictorInput in;
  in.command = 0.02;
  in.answer_step = 5000;
  in.measured_displacement = 0.02;
  in.measured_force = 0.0;
  const double before = ForcePredictor(shaped).step(in).force;
  copy.step(in);
  EXPECT_EQ(ForcePredictor(shaped).step(in).force, before);
}

// A Bouc-Wen specimen (alpha 0.1, yielding to 2.5 x its yield drift) answering 60 steps late,
// the model 30 % off: k and h are fitted apart to the specimen's alpha k0 and (1 - alpha) k0 uy
// (rths identify's F_bw), each with a standard error, and the force is the lag-free one.
TEST(ForcePredictor, AHystereticSpecimenThirtyPercentOffIsFittedInItsStiffnessAndHystereticForce) {
  const double k = 5.0e4, uy = 0.004;
  const BoucWen specimen(k, uy, 0.1, 1.0, 0.5);
  ForcePredictor predictor(declared(0.7 * k), kDt, "bouc-wen", &specimen);
  ASSERT_TRUE(predictor.hysteretic());
  EXPECT_NEAR(predictor.model().hysteretic, 0.7 * 0.9 * k * uy, 1e-9 * k * uy);
  auto remote = specimen.clone(), lag_free = specimen.clone();
  std::vector<double> measured_force, measured_drift;
  double worst = 0.0, peak = 0.0;
  for (long step = 0; step < 6000; ++step) {
    const double t = static_cast<double>(step) * kDt, u = 0.75 * drift(t);
    measured_drift.push_back(u);
    measured_force.push_back(remote->step(u));
    PredictorInput in;
    in.command = u;
    in.command_velocity = 0.75 * drift_rate(t);
    in.answer_step = step - 60;
    if (in.answer_step >= 0) {
      in.measured_displacement = measured_drift[static_cast<std::size_t>(in.answer_step)];
      in.measured_force = measured_force[static_cast<std::size_t>(in.answer_step)];
    }
    const double force = predictor.step(in).force, truth = lag_free->step(u);
    peak = std::max(peak, std::abs(truth));
    if (step >= 3000) worst = std::max(worst, std::abs(force - truth));
  }
  EXPECT_NEAR(predictor.model().stiffness, 0.1 * k, 0.01 * 0.1 * k) << predictor.model_text();
  EXPECT_NEAR(predictor.model().hysteretic, 0.9 * k * uy, 0.01 * 0.9 * k * uy)
      << predictor.model_text();
  EXPECT_LT(std::abs(predictor.model().damping), 0.01 * k * kDt);
  EXPECT_TRUE(std::isfinite(predictor.uncertainty().hysteretic));  // fitted, not held
  EXPECT_LT(worst, 1e-3 * peak) << predictor.model_text();
}

// A Bouc-Wen shape whose yield drift (1 m) the motion never nears, on a spring: z follows x, so
// h cannot be told from k and is held at its start; k takes the rest, the force is the lag-free
// one.
TEST(ForcePredictor, AHysteresisTheDataCannotSeparateIsHeldAndNamedSo) {
  const double k = 5.0e4, uy = 1.0;
  const BoucWen specimen(k, uy, 0.1, 1.0, 0.5);
  ForcePredictor predictor(declared(0.7 * k), kDt, "bouc-wen", &specimen);
  const RemoteLink link{k, 0.0, 60};
  PredictorOutput out;
  for (long step = 0; step < 4000; ++step) out = predictor.step(link.at(step));
  EXPECT_GT(predictor.updates(), 0u);
  EXPECT_EQ(out.hysteretic, 0.7 * 0.9 * k * uy);
  EXPECT_TRUE(std::isnan(predictor.uncertainty().hysteretic));
  EXPECT_NE(predictor.model_text().find("+/- held N"), std::string::npos) << predictor.model_text();
  const PredictorInput in = link.at(4000);
  EXPECT_NEAR(predictor.step(in).force, k * in.command, 0.01 * k * 0.014);
}

// A spring and dashpot (k 5e4 N/m, c_e) read through a first-order load cell of 5 ms, answering
// 60 steps late; the force the integrator used after 6 s against the lag-free one, worst (N).
struct LoadCellRun {
  PredictorTerms model;
  double worst = 0.0;
  std::string text;
};
LoadCellRun through_a_load_cell(double c_e, double declared_lag) {
  const double k_e = 5.0e4, keep = std::exp(-kDt / 0.005);
  PredictorParameters p = declared(0.7 * k_e);
  p.force_lag = declared_lag;
  ForcePredictor predictor(p, kDt);
  std::vector<double> measured_force;
  double cell = 0.0;
  LoadCellRun out;
  for (long step = 0; step < 8000; ++step) {
    const double t = static_cast<double>(step) * kDt;
    cell = keep * cell + (1 - keep) * (k_e * drift(t) + c_e * drift_rate(t));
    measured_force.push_back(cell);
    PredictorInput in;
    in.command = drift(t);
    in.command_velocity = drift_rate(t);
    in.answer_step = step - 60;
    if (in.answer_step >= 0) {
      in.measured_displacement = drift(static_cast<double>(in.answer_step) * kDt);
      in.measured_force = measured_force[static_cast<std::size_t>(in.answer_step)];
    }
    const double force = predictor.step(in).force;
    if (step >= 6000)
      out.worst =
          std::max(out.worst, std::abs(force - (k_e * in.command + c_e * in.command_velocity)));
  }
  out.model = predictor.model();
  out.text = predictor.model_text();
  return out;
}

// The lag term takes the load cell's lag where the dashpot's own phase tells the two apart
// (c w / k ~ 0.5 here): c is the dashpot's and the force the integrator uses is the lag-free
// one. The lag reads short by about a step: the sampled cell is 4.5 ms of backward difference,
// and the measured rate's half-step lag against the dashpot's true rate moves a little of it.
TEST(ForcePredictor, AFirstOrderLoadCellIsFittedAsTheForcesLagAndRemoved) {
  const double c_e = 2000.0;
  const LoadCellRun run = through_a_load_cell(c_e, 0.0);
  EXPECT_GT(run.model.force_lag, 0.0035) << run.text;
  EXPECT_LT(run.model.force_lag, 0.005) << run.text;
  EXPECT_NEAR(run.model.damping, c_e, 0.05 * c_e) << run.text;
  EXPECT_NEAR(run.model.stiffness, 5.0e4, 0.01 * 5.0e4) << run.text;
  EXPECT_LT(run.worst, 0.02 * 5.0e4 * 0.014) << run.text;
}

// A nearly pure spring (c w / k ~ 0.08): its force's lag and its dashpot move the force alike,
// so the data tell only c - k T; the lag term is held at what the lab declared. Undeclared, c
// reads c - k T; declared (the cell's 4.5 ms as sampled), c is the dashpot's and the force the
// lag-free one.
TEST(ForcePredictor, ALagTheDataCannotTellFromTheDashpotIsHeldAtTheDeclaredOne) {
  const double c_e = 300.0, k_e = 5.0e4, sampled_lag = 0.005 - kDt / 2;
  const LoadCellRun undeclared = through_a_load_cell(c_e, 0.0);
  EXPECT_EQ(undeclared.model.force_lag, 0.0) << undeclared.text;
  EXPECT_NEAR(undeclared.model.damping, c_e - k_e * sampled_lag, 0.05 * c_e) << undeclared.text;
  const LoadCellRun declared_lag = through_a_load_cell(c_e, sampled_lag);
  EXPECT_EQ(declared_lag.model.force_lag, sampled_lag) << declared_lag.text;
  EXPECT_NEAR(declared_lag.model.damping, c_e, 0.05 * c_e) << declared_lag.text;
  EXPECT_LT(declared_lag.worst, 0.01 * k_e * 0.014) << declared_lag.text;
  EXPECT_GT(undeclared.worst, 3 * declared_lag.worst);
}

}  // namespace
}  // namespace rths::core
