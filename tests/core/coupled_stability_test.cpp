// The coupled critical delay against the SDOF closed form and against the characteristic equation
// of one delayed storey written independently here (full coordinates, the matrix determinant
// lemma), on the lab's 3-DOF frame.
#include "core/coupled_stability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>
#include <numbers>
#include <optional>

#include "core/envelope_growth.h"
#include "core/restoring_force.h"
#include "core/simulation.h"
#include "core/sparse_structure.h"
#include "core/stability.h"
#include "core/substructure.h"

namespace rths::core {
namespace {

StructuralModel lab_frame() {
  StructuralModel model = make_shear_building({1000, 1000, 800}, {2e6, 2e6, 1.5e6});
  model.damping = rayleigh_damping(model.mass, model.stiffness, 0.03);
  return model;
}

// k_e b b^T for a storey element of stiffness k between DOFs i and j (0-based).
Mat storey_element(int n, int i, int j, double k) {
  Vec b = Vec::Zero(n);
  b[j] = 1.0;
  b[i] = -1.0;
  return k * b * b.transpose();
}

// One delayed link on the drift b' u: its force p(i w) b' u now and h(i w) b' u(t - tau) late,
// with k_e b b^T taken out of K. det(A + z h b b^T) = det(A) (1 + z h b' A^-1 b) with A = K -
// k_e b b' - M w^2 + i w C + p b b', so a root crosses at s = i w when |h g(w)| = 1 with
// g = b' A^-1 b, and then z = e^{-i w tau} = -1 / (h g). Scanned on a linear grid up to
// 5 omega_max and bisected.
template <class Now, class Late>
std::optional<double> one_delayed_link(const StructuralModel& m, const Vec& b, double k, Now now,
                                       Late late) {
  using Complex = std::complex<double>;
  const Mat k_numerical = m.stiffness - k * b * b.transpose();
  const auto g = [&](double w) {
    const Eigen::MatrixXcd a = (k_numerical - w * w * m.mass).cast<Complex>() +
                               Complex(0, w) * m.damping.cast<Complex>() +
                               now(w) * (b * b.transpose()).cast<Complex>();
    return late(w) * Complex(b.cast<Complex>().dot(a.fullPivLu().solve(b.cast<Complex>())));
  };
  const auto excess = [&](double w) { return std::abs(g(w)) - 1.0; };
  std::optional<double> smallest;
  const double top = 5.0 * max_omega(m);
  const int grid = 200000;
  for (int i = 1; i < grid; ++i) {
    double lo = top * (i - 1) / grid + 1e-6, hi = top * i / grid;
    if ((excess(lo) > 0) == (excess(hi) > 0)) continue;
    for (int n = 0; n < 80; ++n) {
      const double mid = 0.5 * (lo + hi);
      ((excess(mid) > 0) == (excess(lo) > 0) ? lo : hi) = mid;
    }
    const double w = 0.5 * (lo + hi);
    double theta = -std::arg(-1.0 / g(w));
    if (theta < 0) theta += 2 * std::numbers::pi;
    if (!smallest || theta / w < *smallest) smallest = theta / w;
  }
  return smallest;
}

// A spring k_e b b^T whose whole force comes back late.
std::optional<double> one_delayed_part(const StructuralModel& m, const Vec& b, double k) {
  return one_delayed_link(
      m, b, k, [](double) { return std::complex<double>(0.0); },
      [k](double) { return std::complex<double>(k); });
}

TEST(CoupledStability, OneDofIsTheSdofClosedForm) {
  const double period = 0.5, zeta = 0.05, alpha = 0.4;
  StructuralModel sdof = make_sdof(period, zeta, 1000.0);
  const Mat k_e = alpha * sdof.stiffness;
  const CoupledStability coupled =
      coupled_critical_delay(sdof, k_e, modal_analysis(sdof.mass, sdof.stiffness));
  const ContinuousStability closed = continuous_critical_delay(period, zeta, alpha);
  ASSERT_TRUE(coupled.critical_delay && closed.critical_delay);
  EXPECT_NEAR(*coupled.critical_delay, *closed.critical_delay, 1e-9 * *closed.critical_delay);
  EXPECT_EQ(coupled.parts, 1);
}

TEST(CoupledStability, AStoreySpecimenAgreesWithItsCharacteristicEquation) {
  const StructuralModel frame = lab_frame();
  for (const double k : {0.5e6, 1e6, 2e6}) {
    const Mat k_e = storey_element(3, 0, 1, k);
    const CoupledStability coupled =
        coupled_critical_delay(frame, k_e, modal_analysis(frame.mass, frame.stiffness));
    const std::optional<double> independent =
        one_delayed_part(frame, Vec::Unit(3, 1) - Vec::Unit(3, 0), k);
    ASSERT_TRUE(coupled.critical_delay.has_value()) << k;
    ASSERT_TRUE(independent.has_value()) << k;
    EXPECT_NEAR(*coupled.critical_delay, *independent, 0.01 * *independent) << k;
    EXPECT_EQ(coupled.modes_kept, 3);
    EXPECT_NE(coupled.assumed.find("all 3 modes"), std::string::npos) << coupled.assumed;
  }
}

TEST(CoupledStability, AStoreyIsNotTheGroundedSpringAtItsFloor) {
  // The researcher's mistake: 0.2e6 N/m of storey 2 as a spring from floor 2 to the ground. As
  // the storey's element it is stable for every lag (its force never outgrows the rest of the
  // storey); as the grounded spring it is not (17 ms, by the independent equation above).
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  Mat grounded = Mat::Zero(3, 3);
  grounded(1, 1) = 0.2e6;
  EXPECT_FALSE(coupled_critical_delay(frame, storey_element(3, 0, 1, 0.2e6), modes)
                   .critical_delay.has_value());
  const auto spring = coupled_critical_delay(frame, grounded, modes);
  const auto independent = one_delayed_part(frame, Vec::Unit(3, 1), 0.2e6);
  ASSERT_TRUE(spring.critical_delay && independent);
  EXPECT_NEAR(*spring.critical_delay, *independent, 0.01 * *independent);
}

TEST(CoupledStability, TwoDelayedStoreysTolerateLessThanEitherAlone) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  const Mat first = storey_element(3, 0, 1, 1e6), second = storey_element(3, 1, 2, 0.75e6);
  const auto both = coupled_critical_delay(frame, first + second, modes);
  const auto one = coupled_critical_delay(frame, first, modes);
  const auto other = coupled_critical_delay(frame, second, modes);
  ASSERT_TRUE(both.critical_delay && one.critical_delay && other.critical_delay);
  EXPECT_EQ(both.parts, 2);
  EXPECT_LT(*both.critical_delay, std::min(*one.critical_delay, *other.critical_delay));
}

TEST(CoupledStability, ProportionalSplitsDecoupleAndKeepTheModalCheck) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  EXPECT_TRUE(modes_decouple(frame, 0.3 * frame.stiffness, modes));
  EXPECT_FALSE(modes_decouple(frame, storey_element(3, 0, 1, 1e6), modes));
  // And the pre-run check says which analysis it used.
  const CriticalDelayCheck check = check_modal_critical_delay(
      frame, storey_element(3, 0, 1, 1e6), IntegratorKind::kExplicitNewmark, 0.001, 0.004);
  EXPECT_NE(check.assumed.find("coupled analysis"), std::string::npos) << check.assumed;
  EXPECT_TRUE(check.modal_continuous.has_value());
  const CriticalDelayCheck proportional = check_modal_critical_delay(
      frame, 0.3 * frame.stiffness, IntegratorKind::kExplicitNewmark, 0.001, 0.004);
  EXPECT_NE(proportional.assumed.find("modal approximation"), std::string::npos);
  EXPECT_FALSE(proportional.modal_continuous.has_value());
}

// The consortium's storey damper (k 3e5 N/m, c 1e4 N s/m between floors 1 and 2, its stiffness
// part of storey 2's) as a link lagging `lag`; with a predictor, its model k^, c^.
DelayedPart storey_damper(double lag, std::optional<std::pair<double, double>> model = {}) {
  DelayedPart part;
  part.row = Vec::Unit(3, 1) - Vec::Unit(3, 0);
  part.stiffness = 3e5;
  part.damping = 1e4;
  part.lag = lag;
  if (model) {
    part.predicted = true;
    part.model_stiffness = model->first;
    part.model_damping = model->second;
  }
  return part;
}

TEST(CoupledLoop, OnOneDofAPredictedLinkIsTheSdofPredictorLimit) {
  const double period = 0.5, zeta = 0.05, alpha = 0.6;
  const StructuralModel sdof = make_sdof(period, zeta);
  const double k = sdof.stiffness(0, 0), omega = 2.0 * std::numbers::pi / period;
  for (const auto& [stiffness_error, damping_error] :
       {std::pair{-0.3, 0.0}, std::pair{-0.5, 0.02}, std::pair{0.4, 0.0}}) {
    DelayedPart part;
    part.row = Vec::Ones(1);
    part.stiffness = alpha * k;
    part.predicted = true;
    part.model_stiffness = (1.0 + stiffness_error) * alpha * k;
    part.model_damping = 2.0 * damping_error * omega;
    const CoupledLoopStability coupled =
        coupled_loop_stability(sdof, {part}, modal_analysis(sdof.mass, sdof.stiffness));
    const ContinuousStability closed =
        predictor_critical_delay(period, zeta, alpha, stiffness_error, damping_error);
    ASSERT_EQ(coupled.parts.size(), 1u);
    ASSERT_EQ(coupled.parts[0].critical_lag.has_value(), closed.critical_delay.has_value())
        << stiffness_error;
    if (closed.critical_delay)
      EXPECT_NEAR(*coupled.parts[0].critical_lag, *closed.critical_delay,
                  1e-9 * *closed.critical_delay)
          << stiffness_error;
  }
}

TEST(CoupledLoop, TheDampersLinkAgreesWithItsCharacteristicEquation) {
  using Complex = std::complex<double>;
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  const Vec b = Vec::Unit(3, 1) - Vec::Unit(3, 0);
  // Uncompensated (the dashpot comes back late too), with a model that misses the dashpot, one
  // 50 % stiff without it (each a finite limit), and one 30 % soft (stable at every lag here).
  const std::vector<std::pair<double, double>> models = {
      {0.0, 0.0}, {3e5, 0.0}, {4.5e5, 0.0}, {2.1e5, 7e3}};
  for (const auto& [k_model, c_model] : models) {
    const bool predicted = k_model > 0;
    const CoupledLoopStability coupled = coupled_loop_stability(
        frame,
        {storey_damper(0.0, predicted ? std::optional(std::pair{k_model, c_model}) : std::nullopt)},
        modes);
    const auto independent = one_delayed_link(
        frame, b, 3e5, [&](double w) { return Complex(k_model, w * c_model); },
        [&](double w) { return Complex(3e5 - k_model, w * (1e4 - c_model)); });
    ASSERT_EQ(coupled.parts[0].critical_lag.has_value(), independent.has_value()) << k_model;
    EXPECT_EQ(coupled.common_critical_lag.has_value(), independent.has_value()) << k_model;
    EXPECT_EQ(independent.has_value(), c_model == 0.0) << k_model;
    if (!independent) continue;
    EXPECT_NEAR(*coupled.parts[0].critical_lag, *independent, 1e-6 * *independent) << k_model;
    EXPECT_NEAR(*coupled.common_critical_lag, *independent, 1e-6 * *independent);
    std::cout << "storey damper, model (" << k_model << " N/m, " << c_model
              << " N s/m): critical lag " << *independent * 1e3 << " ms\n";
  }
}

TEST(CoupledLoop, AnExactModelIsStableAtEveryLagAndTheUncompensatedSpringIsTheOldAnalysis) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  const CoupledLoopStability exact =
      coupled_loop_stability(frame, {storey_damper(0.5, std::pair{3e5, 1e4})}, modes);
  EXPECT_TRUE(exact.stable);
  EXPECT_FALSE(exact.parts[0].critical_lag.has_value());
  DelayedPart spring = storey_damper(0.002);
  spring.damping = 0.0;
  spring.stiffness = 1e6;
  const CoupledLoopStability coupled = coupled_loop_stability(frame, {spring}, modes);
  const CoupledStability old = coupled_critical_delay(frame, storey_element(3, 0, 1, 1e6), modes);
  ASSERT_TRUE(coupled.common_critical_lag && old.critical_delay);
  EXPECT_NEAR(*coupled.common_critical_lag, *old.critical_delay, 1e-9 * *old.critical_delay);
  EXPECT_TRUE(coupled.stable);
  spring.lag = 1.01 * *old.critical_delay;
  const CoupledLoopStability past = coupled_loop_stability(frame, {spring}, modes);
  EXPECT_FALSE(past.stable);
  EXPECT_EQ(past.crossed, 0);
}

// Two links: each one's limit with the other at its own lag. With the other at the common
// critical lag, this one's limit is that same lag (both cross there together); with the other
// past it, the loop has crossed before this link lags at all.
TEST(CoupledLoop, EachLinksLimitHoldsTheOthersAtTheirLags) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  DelayedPart damper = storey_damper(0.0), column;
  column.row = Vec::Unit(3, 2);
  column.stiffness = 0.5e6;
  const CoupledLoopStability common = coupled_loop_stability(frame, {damper, column}, modes);
  ASSERT_TRUE(common.common_critical_lag.has_value());
  const double tau = *common.common_critical_lag;
  column.lag = tau;
  const CoupledLoopStability at = coupled_loop_stability(frame, {damper, column}, modes);
  ASSERT_TRUE(at.parts[0].critical_lag.has_value());
  EXPECT_NEAR(*at.parts[0].critical_lag, tau, 1e-6 * tau);
  damper.lag = 0.9 * tau;
  column.lag = 0.9 * tau;
  EXPECT_TRUE(coupled_loop_stability(frame, {damper, column}, modes).stable);
  column.lag = 3.0 * tau;
  const CoupledLoopStability past = coupled_loop_stability(frame, {damper, column}, modes);
  EXPECT_FALSE(past.stable);
  EXPECT_EQ(past.parts[0].crossed_before, 1);
  EXPECT_LT(past.parts[0].crossed_at, column.lag);
}

// A model held sparse with modal damping keeps C's modes as a low-rank term beside a1 K: the
// coupled analysis reads both (damping_in_modes), as the same C held dense gives.
TEST(CoupledStability, ASparseModelsModalDampingIsRead) {
  const int n = 120;
  StructuralModel sparse =
      make_shear_building(std::vector<double>(n, 1000.0), std::vector<double>(n, 4e7));
  sparse.damping = Mat::Zero(n, n);
  hold_sparse_if_sparse(sparse);
  sparse_modal_damping(sparse, 0.05);
  ASSERT_FALSE(sparse.low_rank_damping.empty());
  StructuralModel dense = sparse;
  const LowRankDamping& low = sparse.low_rank_damping;
  dense.damping = Mat(sparse.sparse_damping) +
                  low.basis * low.coefficients.asDiagonal() * low.basis.transpose();
  dense.sparse_mass.resize(0, 0);
  dense.sparse_damping.resize(0, 0);
  dense.sparse_stiffness.resize(0, 0);
  dense.low_rank_damping = {};
  const Modes modes = modal_analysis(dense.mass, dense.stiffness);
  Mat grounded = Mat::Zero(n, n);
  grounded(0, 0) = 6e7;
  const auto from_sparse = coupled_critical_delay(sparse, grounded, modes);
  const auto from_dense = coupled_critical_delay(dense, grounded, modes);
  StructuralModel stiffness_only = dense;
  stiffness_only.damping = Mat(sparse.sparse_damping);
  const auto without = coupled_critical_delay(stiffness_only, grounded, modes);
  ASSERT_TRUE(from_sparse.critical_delay && from_dense.critical_delay && without.critical_delay);
  EXPECT_NEAR(*from_sparse.critical_delay, *from_dense.critical_delay,
              1e-9 * *from_dense.critical_delay);
  // 43.0 ms against 26.3 ms from a1 K alone.
  EXPECT_GT(*from_sparse.critical_delay, 1.5 * *without.critical_delay);
}

// Each link's row b is row s of B (drifts = B u): a storey's e_s - e_(s-1) in a shear building,
// an element's terms by DOFs, e_d for a grounded specimen; formed O(n) a link, each equal to the
// drift that unit displacements give.
TEST(CoupledLoop, ALinksRowIsItsChannelsRowOfTheDriftMatrix) {
  HybridSetup storeys;
  storeys.model = lab_frame();
  storeys.partition = partition_by_storeys({2e6, 2e6, 1.5e6}, {0, 2}, linear_factory());
  const std::vector<DelayedPart> shear = setup_loop_parts(storeys, {0.0, 0.0});
  ASSERT_EQ(shear.size(), 2u);
  EXPECT_EQ(shear[0].row, Vec::Unit(3, 0));
  EXPECT_EQ(shear[1].row, Vec::Unit(3, 2) - Vec::Unit(3, 1));
  HybridSetup dofs;
  dofs.model = lab_frame();
  std::vector<DofSpecimen> specimens;
  specimens.push_back({2, std::make_unique<LinearSpring>(1e5), ElementRow{}});
  specimens.push_back({1, std::make_unique<LinearSpring>(3e5), ElementRow{{{0, -0.5}, {1, 0.5}}}});
  dofs.partition = partition_by_dofs(dofs.model.stiffness, std::move(specimens));
  const std::vector<DelayedPart> by_dofs = setup_loop_parts(dofs, {0.0, 0.0});
  ASSERT_EQ(by_dofs.size(), 2u);
  EXPECT_EQ(by_dofs[0].row, Vec::Unit(3, 2));
  EXPECT_EQ(by_dofs[1].row, 0.5 * (Vec::Unit(3, 1) - Vec::Unit(3, 0)));
  EXPECT_EQ(by_dofs[1].stiffness, 3e5);
  for (const HybridSetup* setup : {&storeys, &dofs}) {  // against B from unit displacements
    const StoreyAssembly assembly = setup->partition.assembly();
    const std::vector<DelayedPart> parts = setup_loop_parts(*setup, {0.0, 0.0});
    Vec drift(assembly.storeys());
    for (std::size_t a = 0; a < parts.size(); ++a)
      for (int i = 0; i < 3; ++i) {
        assembly.drifts(Vec::Unit(3, i), drift);
        EXPECT_EQ(parts[a].row[i], drift[setup->partition.actuator_storeys[a]]) << a << i;
      }
  }
}

// The frame with the damper behind a shift of `lag` and a frozen predictor (k^, c^; c^ = 1e-6 N
// s/m stands for none: 0 would take the declared dashpot), run in process after a one-step
// ground pulse: the growth rate (1/s) of its storey drift's envelope over the last third of 30 s
// (core::envelope_growth, windows of `period`); +inf when the run stopped at the divergence bound.
double simulated_rate(double lag, double k_model, double c_model, double period) {
  const double dt = 0.001;
  HybridSetup setup;
  setup.model = lab_frame();
  setup.dt = dt;
  std::vector<DofSpecimen> specimens;
  specimens.push_back(
      {1, std::make_unique<InertialSpecimen>(std::make_unique<LinearSpring>(3e5), 0.0, 1e4, dt),
       ElementRow{{{0, -1.0}, {1, 1.0}}}});
  setup.partition = partition_by_dofs(setup.model.stiffness, std::move(specimens));
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(lag, dt));
  setup.delays.push_back(std::move(chain));
  PredictorParameters model;
  model.stiffness = k_model;
  model.damping = c_model;
  model.adapt = false;
  setup.predictors = {model};
  GroundMotion pulse{"pulse", dt, std::vector<double>(30000, 0.0)};
  pulse.acceleration[1] = 1.0;
  const SimulationResult r = simulate(setup, pulse);
  if (r.diverged) return HUGE_VAL;
  std::vector<double> drift(r.steps());
  for (std::size_t k = 0; k < r.steps(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    drift[k] = r.displacement(row, 1) - r.displacement(row, 0);
  }
  const std::optional<EnvelopeGrowth> growth = envelope_growth(drift, dt, period);
  EXPECT_TRUE(growth.has_value()) << lag;
  return growth ? growth->rate : 0.0;
}

// The target: the compensated critical lag against a sweep of in-process runs whose lag
// is bisected on the sign of the envelope's growth, within 5 %. Frozen models that miss the
// dashpot (21.5 ms by the analysis) and that are also 50 % stiff.
TEST(CoupledLoop, TheDampersCompensatedLimitMatchesASweepOfRuns) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  for (const double k_model : {3e5, 4.5e5}) {
    const double c_model = 1e-6;
    const CoupledLoopStability analysed =
        coupled_loop_stability(frame, {storey_damper(0.0, std::pair{k_model, c_model})}, modes);
    ASSERT_TRUE(analysed.parts[0].critical_lag.has_value()) << k_model;
    const double critical = *analysed.parts[0].critical_lag;
    const double period = 2.0 * std::numbers::pi / analysed.parts[0].omega;
    double stable = 0.5 * critical, unstable = 1.5 * critical;
    ASSERT_LT(simulated_rate(stable, k_model, c_model, period), 0.0) << k_model;
    ASSERT_GT(simulated_rate(unstable, k_model, c_model, period), 0.0) << k_model;
    for (int i = 0; i < 10; ++i) {
      const double mid = 0.5 * (stable + unstable);
      (simulated_rate(mid, k_model, c_model, period) > 0.0 ? unstable : stable) = mid;
    }
    const double swept = 0.5 * (stable + unstable);
    std::cout << "storey damper, frozen model (" << k_model << " N/m, no dashpot): analysed "
              << critical * 1e3 << " ms, swept " << swept * 1e3 << " ms ("
              << 100.0 * (critical - swept) / swept << " %)\n";
    EXPECT_NEAR(critical, swept, 0.05 * swept) << k_model;
  }
}

}  // namespace
}  // namespace rths::core
