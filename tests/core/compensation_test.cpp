#include "core/compensation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

#include "core/metrics.h"
#include "study/compensation_config.h"
#include "study/study.h"

namespace rths::core {
namespace {

constexpr double kDt = 1e-3;
constexpr double kShift = 0.0046;         // s, the identified MTS actuator's dead time
constexpr double kTimeConstant = 0.0218;  // s, and its first-order lag

DelayChain mts_actuator(double time_constant = kTimeConstant) {
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(kShift, kDt));
  chain.add(std::make_unique<FirstOrderActuator>(time_constant, kDt));
  return chain;
}

// Two sines (1.3 and 2.9 Hz), amplitude ~ 10 mm, ramped in over the first second.
double excitation(double t) {
  const double ramp = std::min(1.0, t);
  return ramp * (0.01 * std::sin(2 * std::numbers::pi * 1.3 * t) +
                 0.004 * std::sin(2 * std::numbers::pi * 2.9 * t + 0.7));
}

struct Tracking {
  std::vector<double> target, realised;
  double j2_after(std::size_t skip) const {
    return j2_tracking(std::span(target).subspan(skip), std::span(realised).subspan(skip));
  }
};

Tracking track(DelayChain& chain, double seconds) {
  Tracking out;
  const int steps = static_cast<int>(seconds / kDt);
  for (int k = 0; k < steps; ++k) {
    const double t = k * kDt;
    out.target.push_back(excitation(t));
    out.realised.push_back(chain.step({t, excitation(t), 0.0}));
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
TEST(PolynomialExtrapolation, LagrangeWeightsOfFirstOrderOneStepAhead) {
  PolynomialExtrapolation p(1, kDt, 1, kDt);
  ASSERT_EQ(p.weights().size(), 2u);
  EXPECT_DOUBLE_EQ(p.weights()[0], 2.0);
  EXPECT_DOUBLE_EQ(p.weights()[1], -1.0);
}

class PolynomialOrder : public ::testing::TestWithParam<int> {};

TEST_P(PolynomialOrder, ExtrapolatesPolynomialsOfItsOrderExactly) {
  const int order = GetParam();
  constexpr double kLead = 0.0137;  // not a multiple of dt or of the spacing
  constexpr int kSpacing = 3;
  PolynomialExtrapolation p(order, kLead, kSpacing, kDt);
  const auto signal = [order](double t) { return std::pow(1.0 + 2.0 * t, order); };
  double out = 0.0, t = 0.0;
  for (int k = 0; k < 50; ++k) {
    t = k * kDt;
    out = p.step({t, signal(t), 0.0});
  }
  EXPECT_NEAR(out, signal(t + kLead), 1e-12);
  EXPECT_DOUBLE_EQ(p.nominal_lead(), kLead);
  // A polynomial of one order higher is not reproduced: the test can tell the orders apart.
  PolynomialExtrapolation q(order, kLead, kSpacing, kDt);
  const auto higher = [order](double t) { return std::pow(1.0 + 2.0 * t, order + 1); };
  for (int k = 0; k < 50; ++k) out = q.step({k * kDt, higher(k * kDt), 0.0});
  EXPECT_GT(std::abs(out - higher(t + kLead)), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Orders, PolynomialOrder, ::testing::Values(1, 2, 3));

TEST(PolynomialExtrapolation, RefusesOrderLeadAndSpacingThatMakeNoSense) {
  EXPECT_THROW(PolynomialExtrapolation(0, 0.01, 1, kDt), std::invalid_argument);
  EXPECT_THROW(PolynomialExtrapolation(4, 0.01, 1, kDt), std::invalid_argument);
  EXPECT_THROW(PolynomialExtrapolation(2, 0.0, 1, kDt), std::invalid_argument);
  EXPECT_THROW(PolynomialExtrapolation(2, -0.01, 1, kDt), std::invalid_argument);
  EXPECT_THROW(PolynomialExtrapolation(2, 0.01, 0, kDt), std::invalid_argument);
}

TEST(PolynomialExtrapolation, CutsTheTrackingErrorOfTheMtsActuator) {
  DelayChain bare = mts_actuator();
  const double uncompensated = track(bare, 6.0).j2_after(2000);
  DelayChain compensated = mts_actuator();
  compensated.set_compensator(
      std::make_unique<PolynomialExtrapolation>(2, kShift + kTimeConstant, 8, kDt));
  const double with = track(compensated, 6.0).j2_after(2000);
  EXPECT_GT(uncompensated, 20.0);  // % : 26 ms at ~2 Hz
  EXPECT_LT(with, 0.25 * uncompensated);
}

// ---------------------------------------------------------------------------------------------
TEST(AdaptiveTimeSeries, LearnsTheInverseOfShiftPlusFirstOrder) {
  AtsParameters p;
  p.window = 2.0;
  DelayChain chain = mts_actuator();
  auto ats = std::make_unique<AdaptiveTimeSeries>(p, kDt);
  const AdaptiveTimeSeries* view = ats.get();
  chain.set_compensator(std::move(ats));
  const Tracking result = track(chain, 12.0);
  EXPECT_GT(view->updates(), 1000u);
  EXPECT_NEAR(view->a0(), 1.0, 0.02);
  // e^{-s tau} / (1 + s T) inverted: a1 -> T + tau, a2 -> T tau + tau^2 / 2.
  EXPECT_NEAR(view->a1(), kShift + kTimeConstant, 0.1 * (kShift + kTimeConstant));
  EXPECT_NEAR(view->a2(), kShift * kTimeConstant + kShift * kShift / 2, 6e-5);
  const double j2_late =
      j2_tracking(std::span(result.target).subspan(8000), std::span(result.realised).subspan(8000));
  EXPECT_LT(j2_late, 3.0);  // %
}

TEST(AdaptiveTimeSeries, ClampsCoefficientsIntoTheirBounds) {
  AtsParameters p;
  p.window = 1.0;
  p.a1_bounds = {0.0, 0.01};  // the actuator needs ~26 ms
  DelayChain chain = mts_actuator();
  auto ats = std::make_unique<AdaptiveTimeSeries>(p, kDt);
  const AdaptiveTimeSeries* view = ats.get();
  chain.set_compensator(std::move(ats));
  track(chain, 5.0);
  EXPECT_GT(view->updates(), 0u);
  EXPECT_DOUBLE_EQ(view->a1(), 0.01);
}

TEST(AdaptiveTimeSeries, FilteredFitStillFindsTheInverse) {
  AtsParameters p;
  p.window = 2.0;
  p.derivative_cutoff = 20.0;  // Hz: the same filter on command and measurement cancels out
  DelayChain chain = mts_actuator();
  auto ats = std::make_unique<AdaptiveTimeSeries>(p, kDt);
  const AdaptiveTimeSeries* view = ats.get();
  chain.set_compensator(std::move(ats));
  track(chain, 10.0);
  EXPECT_NEAR(view->a1(), kShift + kTimeConstant, 0.1 * (kShift + kTimeConstant));
}

TEST(AdaptiveTimeSeries, RefusesBadWindowBoundsAndCutoff) {
  AtsParameters p;
  p.window = 2e-3;  // < 3 dt
  EXPECT_THROW(AdaptiveTimeSeries(p, kDt), std::invalid_argument);
  p = {};
  p.a1_bounds = {0.05, 0.01};
  try {
    AdaptiveTimeSeries(p, kDt);
    FAIL() << "min > max accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a1_bounds"), std::string::npos) << e.what();
  }
  p = {};
  p.a1 = 0.5;  // outside [0, 0.1]
  EXPECT_THROW(AdaptiveTimeSeries(p, kDt), std::invalid_argument);
  p = {};
  p.derivative_cutoff = 600.0;  // above Nyquist at 1 kHz
  EXPECT_THROW(AdaptiveTimeSeries(p, kDt), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
PlantModel mts_plant(double time_constant = kTimeConstant) {
  PlantModel plant;
  plant.delay = kShift;
  plant.append({1.0}, {time_constant, 1.0});
  return plant;
}

TEST(ModelBasedInverse, IsProperWithUnitStaticGainAndTheDesignedLead) {
  constexpr double kRolloff = 40.0;
  const ModelBasedInverse c(mts_plant(), 2, kRolloff, kDt);
  EXPECT_EQ(c.numerator().size(), c.denominator().size());  // proper, not strictly
  EXPECT_NEAR(c.numerator().back() / c.denominator().back(), 1.0, 1e-12);
  const double filter_lag = 3.0 / (2 * std::numbers::pi * kRolloff);
  EXPECT_NEAR(c.total_lead(), kShift + filter_lag, 1e-12);
  // Low-frequency lead of the whole block: the inverse's T plus the delay lead.
  EXPECT_NEAR(c.nominal_lead(), kTimeConstant + kShift, 1e-9);
  // A step settles on the target (unit static gain), through a causal response.
  ModelBasedInverse step_response(mts_plant(), 2, kRolloff, kDt);
  double out = 0.0;
  for (int k = 0; k < 2000; ++k) out = step_response.step({k * kDt, 1.0, 0.0});
  EXPECT_NEAR(out, 1.0, 1e-9);
}

TEST(ModelBasedInverse, TracksThroughTheActuatorItWasDesignedFor) {
  DelayChain chain = mts_actuator();
  chain.set_compensator(std::make_unique<ModelBasedInverse>(mts_plant(), 2, 40.0, kDt));
  const Tracking result = track(chain, 6.0);
  EXPECT_LT(result.j2_after(2000), 1.0);  // %
  EXPECT_LT(std::abs(j1_delay(result.target, result.realised, kDt, 0.05)), 1e-3);
}

TEST(ModelBasedInverse, RefusesRightHalfPlaneZerosOrdersAndRolloff) {
  PlantModel nonminimum;
  nonminimum.append({-0.01, 1.0}, {0.001, 0.05, 1.0});  // zero at s = +100
  try {
    ModelBasedInverse(nonminimum, 2, 40.0, kDt);
    FAIL() << "right-half-plane zero accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("left half-plane"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ModelBasedInverse(mts_plant(), 0, 40.0, kDt), std::invalid_argument);
  EXPECT_THROW(ModelBasedInverse(mts_plant(), 4, 40.0, kDt), std::invalid_argument);
  EXPECT_THROW(ModelBasedInverse(mts_plant(), 2, 0.0, kDt), std::invalid_argument);
  EXPECT_THROW(ModelBasedInverse(mts_plant(), 2, 300.0, kDt), std::invalid_argument);
  PlantModel improper;
  improper.append({1.0, 1.0}, {1.0});
  EXPECT_THROW(ModelBasedInverse(improper, 2, 40.0, kDt), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// The nominal design (4.6 ms + 21.8 ms, roll-off 40 Hz) with its adaptive correction, in front of
// an actuator whose shift and time constant are `scale` times the nominal ones.
struct AdaptedRun {
  Tracking tracking;
  double a0 = 0, a1 = 0, a2 = 0;
  std::size_t updates = 0;
  bool stayed_in_bounds = true;
};

AdaptedRun run_adapted(double scale, const AtsParameters& correction, double seconds) {
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(scale * kShift, kDt));
  chain.add(std::make_unique<FirstOrderActuator>(scale * kTimeConstant, kDt));
  auto block = std::make_unique<AdaptedModelBasedInverse>(
      ModelBasedInverse(mts_plant(), 2, 40.0, kDt), correction, kDt);
  const AdaptiveTimeSeries& view = block->correction();
  chain.set_compensator(std::move(block));
  AdaptedRun out;
  const int steps = static_cast<int>(seconds / kDt);
  for (int k = 0; k < steps; ++k) {
    const double t = k * kDt;
    out.tracking.target.push_back(excitation(t));
    out.tracking.realised.push_back(chain.step({t, excitation(t), 0.0}));
    const bool inside =
        view.a0() >= correction.a0_bounds.min && view.a0() <= correction.a0_bounds.max &&
        view.a1() >= correction.a1_bounds.min && view.a1() <= correction.a1_bounds.max &&
        view.a2() >= correction.a2_bounds.min && view.a2() <= correction.a2_bounds.max;
    out.stayed_in_bounds = out.stayed_in_bounds && inside;
  }
  out.a0 = view.a0();
  out.a1 = view.a1();
  out.a2 = view.a2();
  out.updates = view.updates();
  return out;
}

TEST(AdaptedModelBasedInverse, LearnsTheResidualLagOfAWrongModel) {
  AtsParameters correction = adaptive_correction_defaults();
  correction.window = 2.0;
  // With the model right the correction stays at the identity.
  const AdaptedRun right = run_adapted(1.0, correction, 10.0);
  EXPECT_GT(right.updates, 1000u);
  EXPECT_NEAR(right.a0, 1.0, 0.02);
  EXPECT_NEAR(right.a1, 0.0, 1e-3);
  // Lag 30 % longer / shorter: a1 -> (tau' - tau) + (T' - T) = +-0.3 (4.6 + 21.8) ms = +-7.92 ms.
  for (double scale : {1.3, 0.7}) {
    const AdaptedRun wrong = run_adapted(scale, correction, 10.0);
    const double residual = (scale - 1.0) * (kShift + kTimeConstant);
    EXPECT_NEAR(wrong.a0, 1.0, 0.03) << scale;
    EXPECT_NEAR(wrong.a1 - right.a1, residual, 0.1 * std::abs(residual)) << scale;
    EXPECT_TRUE(wrong.stayed_in_bounds) << scale;
    EXPECT_LT(wrong.tracking.j2_after(4000), 2.0)
        << scale;  // %, once the window has adapted (1.0, 0.65)
    EXPECT_LT(std::abs(j1_delay(std::span(wrong.tracking.target).subspan(4000),
                                std::span(wrong.tracking.realised).subspan(4000), kDt, 0.05)),
              0.5e-3)
        << scale;
  }
  // The fixed feedforward against the same wrong actuator: what the correction removes.
  DelayChain slow;
  slow.add(std::make_unique<TimeShift>(1.3 * kShift, kDt));
  slow.add(std::make_unique<FirstOrderActuator>(1.3 * kTimeConstant, kDt));
  slow.set_compensator(std::make_unique<ModelBasedInverse>(mts_plant(), 2, 40.0, kDt));
  EXPECT_GT(track(slow, 10.0).j2_after(4000), 5.0);
}

TEST(AdaptedModelBasedInverse, ClampsTheCorrectionIntoItsBounds) {
  AtsParameters correction = adaptive_correction_defaults();
  correction.a1_bounds = {-0.002, 0.002};  // s: the 30 % slower actuator needs ~ 7.9 ms
  const AdaptedRun clamped = run_adapted(1.3, correction, 5.0);
  EXPECT_GT(clamped.updates, 0u);
  EXPECT_TRUE(clamped.stayed_in_bounds);
  EXPECT_DOUBLE_EQ(clamped.a1, 0.002);
}

TEST(AdaptedModelBasedInverse, StartsAtTheIdentityAndRefusesBoundsWithoutIt) {
  const ModelBasedInverse inverse(mts_plant(), 2, 40.0, kDt);
  AtsParameters p = adaptive_correction_defaults();
  AdaptedModelBasedInverse fresh(inverse, p, kDt);
  EXPECT_EQ(fresh.correction().a0(), 1.0);
  EXPECT_EQ(fresh.correction().a1(), 0.0);
  EXPECT_EQ(fresh.correction().a2(), 0.0);
  // Before its window fills it is exactly the fixed feedforward.
  ModelBasedInverse alone = inverse;
  for (int k = 0; k < 500; ++k) {
    const CompensatorInput in{k * kDt, excitation(k * kDt), 0.5 * excitation(k * kDt)};
    ASSERT_EQ(fresh.step(in), alone.step(in)) << k;
  }
  const auto message = [&](const AtsParameters& bad) -> std::string {
    try {
      AdaptedModelBasedInverse(inverse, bad, kDt);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  p.a1_bounds = {0.001, 0.05};  // excludes a1 = 0, the nominal design
  EXPECT_NE(message(p).find("a1_bounds"), std::string::npos) << message(p);
  p = adaptive_correction_defaults();
  p.a0_bounds = {1.2, 2.0};
  EXPECT_NE(message(p).find("a0_bounds"), std::string::npos) << message(p);
  p = adaptive_correction_defaults();
  p.a2 = 1e-4;  // not the identity
  EXPECT_NE(message(p).find("a2 must start at 0"), std::string::npos) << message(p);
  p = adaptive_correction_defaults();
  p.window = 2e-3;  // < 3 dt
  EXPECT_NE(message(p).find("window"), std::string::npos) << message(p);
}

// ---------------------------------------------------------------------------------------------
TEST(Polynomials, MultiplyAndRoots) {
  EXPECT_EQ(polynomial_multiply({1.0, 1.0}, {1.0, -2.0}), (std::vector<double>{1.0, -1.0, -2.0}));
  auto roots = polynomial_roots({1.0, -1.0, -2.0});
  ASSERT_EQ(roots.size(), 2u);
  std::sort(roots.begin(), roots.end(), [](auto a, auto b) { return a.real() < b.real(); });
  EXPECT_NEAR(roots[0].real(), -1.0, 1e-12);
  EXPECT_NEAR(roots[1].real(), 2.0, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Records what the chain hands a compensator, and passes the target through.
class Probe final : public Compensator {
 public:
  explicit Probe(std::vector<CompensatorInput>* seen) : seen_(seen) {}
  double step(const CompensatorInput& in) override {
    seen_->push_back(in);
    return 2.0 * in.target;
  }
  void reset() override {}
  std::unique_ptr<Compensator> clone() const override { return std::make_unique<Probe>(*this); }
  std::string describe() const override { return "probe"; }
  double nominal_lead() const override { return 0.003; }

 private:
  std::vector<CompensatorInput>* seen_;
};

TEST(DelayChainCompensation, CompensatorSeesTargetAndThePreviousOutput) {
  std::vector<CompensatorInput> seen;
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(kDt, kDt));  // one step late
  chain.set_compensator(std::make_unique<Probe>(&seen));
  EXPECT_FALSE(chain.empty());
  EXPECT_NEAR(chain.nominal_delay(), kDt - 0.003, 1e-15);
  std::vector<double> outputs;
  for (int k = 0; k < 4; ++k) outputs.push_back(chain.step({k * kDt, 1.0 + k, 0.0}));
  ASSERT_EQ(seen.size(), 4u);
  EXPECT_DOUBLE_EQ(seen[0].measured, 0.0);
  for (int k = 1; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(seen[k].target, 1.0 + k);
    EXPECT_DOUBLE_EQ(seen[k].measured, outputs[k - 1]);
  }
  EXPECT_DOUBLE_EQ(outputs[3], 2.0 * 3.0);  // the shaped command, one step late
  EXPECT_NE(chain.describe().find("probe"), std::string::npos);
  // A copy carries its own compensator; reset forgets the previous output.
  DelayChain copy = chain;
  copy.reset();
  seen.clear();
  copy.step({0.0, 1.0, 0.0});
  EXPECT_DOUBLE_EQ(seen[0].measured, 0.0);
}

// ---------------------------------------------------------------------------------------------
std::string study_with(const std::string& compensation) {
  return R"(
structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }
motion { path: "unused.AT2" }
integrator { dt: 0.001 }
substructuring { experimental_fraction: 0.5 }
cases { name: "reference" }
cases { name: "compensated" delay { shift { delay: 0.0046 } } delay { first_order { time_constant: 0.0218 } } )" +
         compensation + " }\n";
}

std::string error_of(const std::string& compensation) {
  try {
    study::parse_study(study_with(compensation), "study.textproto");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CompensationConfig, BadFieldsAreNamed) {
  EXPECT_NE(error_of("compensation { polynomial { order: 5 lead: 0.02 } }")
                .find("cases[1] 'compensated' compensation[0].polynomial.order"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { polynomial { order: 2 lead: -0.02 } }")
                .find("compensation[0].polynomial.lead"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { adaptive_time_series { window: 0 } }")
                .find("adaptive_time_series.window"),
            std::string::npos);
  EXPECT_NE(
      error_of("compensation { adaptive_time_series { window: 1 a0_bounds { min: 2 max: 1 } } }")
          .find("a0_bounds"),
      std::string::npos);
  EXPECT_NE(error_of("compensation { model_based { lead_order: 2 rolloff_frequency: 40 } }")
                .find("model_based.plant is empty"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { model_based { plant { jitter { mean_delay: 0.01 } } "
                     "lead_order: 2 rolloff_frequency: 40 } }")
                .find("model_based.plant[0]"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { model_based { plant { first_order { time_constant: 0.02 } } "
                     "lead_order: 7 rolloff_frequency: 40 } }")
                .find("model_based.lead_order"),
            std::string::npos);
  const std::string inverse =
      "model_based { plant { first_order { time_constant: 0.02 } } lead_order: 2 "
      "rolloff_frequency: 40 ";
  EXPECT_NE(error_of("compensation { " + inverse + "adaptive_correction { window: 0 } } }")
                .find("compensation[0].model_based.adaptive_correction.window"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { " + inverse +
                     "adaptive_correction { window: 1 a1_bounds { min: 0.01 max: 0.05 } } } }")
                .find("compensation[0].model_based.adaptive_correction: a1_bounds"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { " + inverse +
                     "adaptive_correction { window: 1 a2_bounds { min: 0.001 max: -0.001 } } } }")
                .find("compensation[0].model_based.adaptive_correction: a2_bounds"),
            std::string::npos);
  EXPECT_NE(error_of("compensation { " + inverse +
                     "adaptive_correction { window: 1 derivative_cutoff: -5 } } }")
                .find("model_based.adaptive_correction.derivative_cutoff"),
            std::string::npos);
  EXPECT_EQ(error_of("compensation { " + inverse + "adaptive_correction { window: 1 } } }"), "");
  EXPECT_NE(error_of("compensation { }").find("has no kind"), std::string::npos);
  EXPECT_EQ(error_of("compensation { polynomial { order: 2 lead: 0.02 } }"), "");
}

TEST(CompensationConfig, DtDependentFieldsAreNamedWhenBuilt) {
  config::Compensation c;
  c.mutable_polynomial()->set_order(2);
  c.mutable_polynomial()->set_lead(0.02);
  c.mutable_polynomial()->set_spacing(0.0025);
  try {
    study::make_compensator(c, kDt, "case 'x' compensation[0]");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("compensation[0].polynomial.spacing"), std::string::npos)
        << e.what();
  }
  config::Compensation m;
  m.mutable_model_based()->add_plant()->mutable_first_order()->set_time_constant(0.02);
  m.mutable_model_based()->set_lead_order(2);
  m.mutable_model_based()->set_rolloff_frequency(400.0);  // above fs / 4 at 1 kHz
  try {
    study::make_compensator(m, kDt, "case 'x' compensation[0]");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("compensation[0].model_based: rolloff_frequency"),
              std::string::npos)
        << e.what();
  }
}

TEST(CompensationConfig, AdaptiveCorrectionBuildsWithItsDefaultsAndNamesDtDependentFields) {
  config::Compensation c;
  auto* m = c.mutable_model_based();
  m->add_plant()->mutable_shift()->set_delay(kShift);
  m->add_plant()->mutable_first_order()->set_time_constant(kTimeConstant);
  m->set_lead_order(2);
  m->set_rolloff_frequency(40.0);
  m->mutable_adaptive_correction()->set_window(1.0);
  const std::unique_ptr<Compensator> block =
      study::make_compensator(c, kDt, "case 'x' compensation[0]");
  const auto* adapted = dynamic_cast<const AdaptedModelBasedInverse*>(block.get());
  ASSERT_NE(adapted, nullptr) << block->describe();
  EXPECT_NE(block->describe().find("adaptive correction"), std::string::npos);
  EXPECT_NEAR(block->nominal_lead(), kShift + kTimeConstant, 1e-9);
  m->mutable_adaptive_correction()->set_window(0.002);  // < 3 dt
  try {
    study::make_compensator(c, kDt, "case 'x' compensation[0]");
    FAIL() << "a window of two steps accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("compensation[0].model_based.adaptive_correction: window"),
              std::string::npos)
        << e.what();
  }
  m->mutable_adaptive_correction()->set_window(1.0);
  m->mutable_adaptive_correction()->set_derivative_cutoff(800.0);  // above Nyquist at 1 kHz
  try {
    study::make_compensator(c, kDt, "case 'x' compensation[0]");
    FAIL() << "a cut-off above Nyquist accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("model_based.adaptive_correction: derivative_cutoff"),
              std::string::npos)
        << e.what();
  }
}

TEST(CompensationConfig, PlantFromStagesMultipliesAndAddsDelays) {
  config::Case c;
  c.add_delay()->mutable_shift()->set_delay(0.003);
  auto* first = c.add_delay();
  first->mutable_first_order()->set_time_constant(0.02);
  first->set_amplitude_gain(0.9);
  c.add_delay()->mutable_shift()->set_delay(0.001);
  const PlantModel plant = study::plant_from_stages(c.delay(), "plant");
  EXPECT_DOUBLE_EQ(plant.delay, 0.004);
  EXPECT_DOUBLE_EQ(plant.gain, 0.9);
  EXPECT_EQ(plant.denominator, (std::vector<double>{0.02, 1.0}));
}

// ---------------------------------------------------------------------------------------------
// The shipped study: the identified MTS actuator on the paper's frame (first 15 s of the record).
TEST(PaperFrameCompensated, CompensatorsBringTheTestBackFromSevenHundredPercent) {
  const std::filesystem::path config =
      std::filesystem::path(RTHS_SOURCE_DIR) / "configs/paper_frame_compensated.textproto";
  config::Study study = study::load_study(config);
  study.mutable_motion()->set_duration(15.0);
  const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
  const auto top = [](const SimulationResult& r) {
    std::vector<double> u(r.steps());
    for (std::size_t k = 0; k < u.size(); ++k)
      u[k] = r.displacement(static_cast<Eigen::Index>(k), 0);
    return u;
  };
  const auto run = [&](const std::string& name) {
    for (const auto& c : study.cases())
      if (c.name() == name) return simulate(study::setup_for_case(prepared, c), prepared.motion);
    throw std::runtime_error("no case " + name);
  };
  const std::vector<double> reference = top(run("reference"));
  const auto error_of = [&](const std::string& name) { return nrmse(reference, top(run(name))); };
  EXPECT_GT(error_of("uncompensated"), 2.0);
  EXPECT_LT(error_of("model_based"), 0.05);
  EXPECT_LT(error_of("ats"), 0.05);
  EXPECT_LT(error_of("ats_lag_plus_30pct"), 0.15);
  EXPECT_LT(error_of("ats_lag_minus_30pct"), 0.15);
  const SimulationResult mb = run("model_based");
  std::vector<double> target(mb.steps()), realised(mb.steps());
  for (std::size_t k = 0; k < mb.steps(); ++k) {
    target[k] = mb.command(static_cast<Eigen::Index>(k), 0);
    realised[k] = mb.realised(static_cast<Eigen::Index>(k), 0);
  }
  EXPECT_LT(std::abs(j1_delay(target, realised, mb.dt, 0.1)), 1e-3);
  EXPECT_LT(j2_tracking(target, realised), 5.0);
}

// The missed target of issue 13: the model-based design for the nominal actuator, run against an
// actuator whose lag is 30 % off, stays <= 15 % NRMSE with the adaptive correction (the fixed
// feedforward gives 36-45 %). First 12 s of the record.
TEST(PaperFrameCompensated, AdaptedModelBasedStaysWithinFifteenPercentWithTheLagThirtyPercentOff) {
  const std::filesystem::path config =
      std::filesystem::path(RTHS_SOURCE_DIR) / "configs/paper_frame_compensated.textproto";
  config::Study study = study::load_study(config);
  study.mutable_motion()->set_duration(12.0);
  const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
  const auto run = [&](const std::string& name) {
    for (const auto& c : study.cases())
      if (c.name() == name) return simulate(study::setup_for_case(prepared, c), prepared.motion);
    throw std::runtime_error("no case " + name);
  };
  const auto top = [](const SimulationResult& r) {
    std::vector<double> u(r.steps());
    for (std::size_t k = 0; k < u.size(); ++k)
      u[k] = r.displacement(static_cast<Eigen::Index>(k), 0);
    return u;
  };
  const std::vector<double> reference = top(run("reference"));
  for (const std::string name : {"model_based_adaptive", "model_based_adaptive_lag_plus_30pct",
                                 "model_based_adaptive_lag_minus_30pct"}) {
    const SimulationResult r = run(name);
    ASSERT_FALSE(r.diverged) << name;
    const bool nominal = name == "model_based_adaptive";
    EXPECT_LT(nrmse(reference, top(r)), nominal ? 0.05 : 0.15) << name;
    std::vector<double> target(r.steps()), realised(r.steps());
    for (std::size_t k = 0; k < r.steps(); ++k) {
      target[k] = r.command(static_cast<Eigen::Index>(k), 0);
      realised[k] = r.realised(static_cast<Eigen::Index>(k), 0);
    }
    EXPECT_LT(std::abs(j1_delay(target, realised, r.dt, 0.1)), 1e-3) << name;
    EXPECT_LT(j2_tracking(target, realised), 5.0) << name;
  }
  // The fixed feedforward against the slower actuator misses the target: the correction is needed.
  EXPECT_GT(nrmse(reference, top(run("model_based_lag_plus_30pct"))), 0.15);
}

}  // namespace
}  // namespace rths::core
