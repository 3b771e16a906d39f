#pragma once
// Delay compensation: blocks that shape the command sent to an actuator so that what the actuator
// realises follows what the integrator wanted. A compensator only shapes the command: the
// measured displacement and the measured force go back to the integrator unchanged.
//
// Input  (CompensatorInput): t (s), the target x_t (m, the displacement the integrator computed
//        for this step) and x_m (m, the displacement the actuator realised one step earlier, as
//        its sensor read it: the measured feedback a servo controller has when it shapes the
//        next command).
// Output: the command u_c (m) given to the actuator (the delay chain of core/delay.h).
// Called once per step with spacing dt; deterministic, so in-process and lockstep distributed
// runs agree bit for bit. Initial state: at rest (every past target and measurement is 0).
// step() is real-time safe: every buffer is sized at construction.
//
// Equations:
//   PolynomialExtrapolation (Horiuchi, Inoue, Konno & Namita 1999, Earthquake Engng Struct. Dyn.
//     28(10), 1121-1141): the polynomial of order n (1..3) through the last n+1 targets, spaced
//     h = s dt apart (s >= 1 steps), evaluated a lead L ahead:
//       u_c[k] = sum_{j=0..n} c_j x_t[k - j s],  c_j = prod_{m != j} (L/h + m) / (m - j)
//     (Lagrange weights for the nodes 0, -h, .., -n h). Exact for polynomials of order <= n.
//   AdaptiveTimeSeries, ATS (Chae, Kazemibidokhti & Ricles 2013, Earthquake Engng Struct. Dyn.
//     42(11), 1697-1715):
//       u_c[k] = a0 x_t + a1 x_t' + a2 x_t''   (derivatives of the target: second-order backward
//       differences x' = (3x_k - 4x_{k-1} + x_{k-2}) / 2dt, x'' = (2x_k - 5x_{k-1} + 4x_{k-2}
//       - x_{k-3}) / dt^2, exact for quadratics / cubics).
//     The coefficients are the least-squares fit of the actuator's inverse over a moving window of
//     W samples of past commands and measurements:  u_c ~ a0 x_m + a1 x_m' + a2 x_m'' (the same
//     difference operators as on the target, so a1 and a2 are the ones the command law needs).
//     Before the fit both u_c and x_m pass the same first-order low-pass (cut-off f_c; the filter on
//     the derivatives): a linear relation with constant coefficients survives an identical
//     filter on both sides, so the filter does not bias the coefficients. The fit is refreshed
//     every step once the window is full and its (column-scaled) normal matrix is well conditioned;
//     each coefficient is then clamped into its bounds [min_i, max_i].
//     For an actuator e^{-s tau} / (1 + s T): a0 -> 1, a1 -> T + tau, a2 -> T tau + tau^2 / 2.
//   ModelBasedInverse (feedforward inverse of an identified plant, e.g. Carrion & Spencer 2007,
//     Newmark Structural Engineering Laboratory report 9; Chen & Tsai 2013): for the plant
//       G(s) = g e^{-s tau} N(s) / D(s)   (N Hurwitz: minimum phase; relative degree r_p >= 0)
//     the compensator is
//       C(s) = D(s) T_m(s L) / (g N(s) (1 + s / w_f)^(r_p + m)),   L = tau + (r_p + m) / w_f,
//     T_m(x) = sum_{i=0..m} x^i / i! the Taylor polynomial of e^x (the delay lead, m = 1..3),
//     w_f = 2 pi f_rolloff. The roll-off makes C proper (causal); its own low-frequency lag
//     (r_p + m) / w_f is added to the lead so that G C -> 1 (gain and phase) at low frequency.
//     Tustin-discretised (core::TransferFunctionStage).
//   AdaptedModelBasedInverse (the model-based feedforward with an online-adapted correction, as
//     labs add it when the identified model may be off: Chae, Kazemibidokhti & Ricles 2013 for
//     the adaptation, Carrion & Spencer 2007 for the feedforward): the chain
//       x_t -> A -> C(s) -> actuator G -> x_m,   v = A x_t = a0 x_t + a1 x_t' + a2 x_t'',
//     C the ModelBasedInverse above, A an AdaptiveTimeSeries started from the identity
//     (a0 = 1, a1 = a2 = 0: the nominal design) whose least-squares fit runs on (v, x_m) over
//     its moving window. The plant A adapts to is C G, which is 1 when the model is right, so
//     its coefficients are the residual: for a true actuator e^{-s tau'} / (1 + s T') and a
//     design for (tau, T), C G ~ e^{-s (tau' - tau)} (1 + s T) / (1 + s T') and
//       a0 -> 1,  a1 -> (tau' - tau) + (T' - T)   (s; negative when the actuator is faster),
//       a2 -> the second-order residual (s^2).
//     A sits in front of C in the signal path: after C it would see G alone and learn G^{-1},
//     compensating twice. With frozen coefficients the two linear blocks commute, so this is
//     "C followed by a correction" of the loop. Bounds clamp each coefficient (config
//     model_based.adaptive_correction: a0 [0.5, 2], a1 [-0.05, 0.05] s, a2 [-1e-3, 1e-3] s^2
//     when absent; each must contain the identity). Time-varying: a discrete stability analysis
//     is of the frozen coefficients (core/stability.h).
//
// Linear dynamics (core/linear_dynamics.h), from x_t to u_c (x_m does not enter a frozen block):
//   PolynomialExtrapolation   H = sum_j c_j e^{-i w j h},  h = s dt; the register of the last
//                             n s targets.                                   (time-invariant)
//   AdaptiveTimeSeries        H = a0 + a1 i w - a2 w^2 at the present coefficients; realised with
//                             the backward differences above.  (kFrozen: "time-varying ...")
//   ModelBasedInverse         H = C(i w); realised as its Tustin filter.     (time-invariant)
//   AdaptedModelBasedInverse  H = A(i w) C(i w), A the frozen correction.   (kFrozen)
// A Compensator that does not state them (the base's default) is not representable (kNone).

#include <complex>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/compensator.h"
#include "core/delay.h"

namespace rths::core {

class PolynomialExtrapolation final : public Compensator {
 public:
  // @pre order in 1..3, 0 < lead <= 1 s, spacing_steps >= 1, dt > 0. Throws std::invalid_argument.
  PolynomialExtrapolation(int order, double lead, int spacing_steps, double dt);
  double step(const CompensatorInput& in) override;
  void reset() override;
  std::unique_ptr<Compensator> clone() const override;
  std::string describe() const override;
  double nominal_lead() const override { return lead_; }
  const std::vector<double>& weights() const { return weights_; }  // c_0..c_n
  Linearity linearity() const override { return {}; }
  std::complex<double> frequency_response(double omega) const override;
  LinearBlock state_space() const override;

 private:
  int order_, spacing_;
  double lead_, dt_;
  std::vector<double> weights_;
  std::vector<double> history_;  // ring of the last order * spacing + 1 targets
  std::size_t head_ = 0;
};

struct CoefficientBounds {
  double min = 0.0, max = 0.0;
};

struct AtsParameters {
  double window = 1.0;                       // s of samples in the least-squares fit
  double a0 = 1.0, a1 = 0.0, a2 = 0.0;       // initial coefficients (-, s, s^2)
  CoefficientBounds a0_bounds{0.5, 2.0};     // -
  CoefficientBounds a1_bounds{0.0, 0.1};     // s
  CoefficientBounds a2_bounds{-0.01, 0.01};  // s^2
  double derivative_cutoff = 0.0;            // Hz, low-pass before differentiating; 0 = none
};

class AdaptiveTimeSeries final : public Compensator {
 public:
  // Throws std::invalid_argument "LABEL: PARAMETER ..." naming the parameter (window < 3 dt,
  // min >= max, an initial coefficient outside its bounds, a cut-off <= 0 or above the Nyquist
  // frequency...); `label` names the block (a config path when built from one).
  AdaptiveTimeSeries(const AtsParameters& parameters, double dt,
                     const std::string& label = "adaptive time series compensator");
  double step(const CompensatorInput& in) override;
  void reset() override;
  std::unique_ptr<Compensator> clone() const override;
  std::string describe() const override;
  double nominal_lead() const override { return 0.0; }
  double a0() const { return a_[0]; }
  double a1() const { return a_[1]; }
  double a2() const { return a_[2]; }
  std::size_t updates() const { return updates_; }  // fits accepted so far
  // kFrozen, stating the present coefficients; H and the realisation are at them.
  Linearity linearity() const override;
  std::complex<double> frequency_response(double omega) const override;
  LinearBlock state_space() const override;

 private:
  void learn(double command, double measured);
  void fit();

  AtsParameters p_;
  double dt_, filter_decay_;
  double a_[3];
  double target_[4] = {0, 0, 0, 0};             // x_t[k], x_t[k-1], ..
  double filtered_measured_[4] = {0, 0, 0, 0};  // low-passed x_m, newest first
  double filtered_command_ = 0.0, last_command_ = 0.0;
  bool has_previous_ = false;  // a command was sent, so in.measured answers it
  std::size_t samples_seen_ = 0, updates_ = 0;
  // Regression rows over the window: [x, x', x''] of the filtered measurement, and the filtered
  // command they must explain.
  std::vector<double> rows_x_, rows_v_, rows_a_, rows_u_;
  std::size_t row_head_ = 0, row_count_ = 0;
};

// C(s) above, and its total lead L (s).
struct InverseDesign {
  std::vector<double> numerator, denominator;
  double lead = 0.0;
};
// Throws as ModelBasedInverse's constructor.
InverseDesign design_inverse(const PlantModel& plant, int lead_order, double rolloff_hz, double dt,
                             const std::string& label = "model-based compensator");

class ModelBasedInverse final : public Compensator {
 public:
  // Throws std::invalid_argument naming the parameter: lead_order outside 1..3, rolloff <= 0 or
  // at or above a quarter of the sampling rate, a plant with a zero gain, a right-half-plane zero
  // (its inverse would be unstable), a pole at s = 0, or more zeros than poles; the message
  // opens with `label` (a config path when built from one).
  ModelBasedInverse(PlantModel plant, int lead_order, double rolloff_hz, double dt,
                    const std::string& label = "model-based compensator");
  double step(const CompensatorInput& in) override;
  void reset() override { filter_.reset(); }
  std::unique_ptr<Compensator> clone() const override;
  std::string describe() const override;
  double nominal_lead() const override { return -filter_.nominal_delay(); }
  // The continuous compensator C(s), highest power first (for stability analysis and tests).
  const std::vector<double>& numerator() const { return numerator_; }
  const std::vector<double>& denominator() const { return denominator_; }
  double total_lead() const { return lead_; }                      // L above (s)
  const TransferFunctionStage& filter() const { return filter_; }  // the Tustin-discretised C
  Linearity linearity() const override { return {}; }
  std::complex<double> frequency_response(double omega) const override;
  LinearBlock state_space() const override { return filter_.state_space(); }
  std::optional<PlantModel> transfer_function() const override;

 private:
  ModelBasedInverse(PlantModel plant, int lead_order, double rolloff_hz, double dt,
                    const InverseDesign& design);
  PlantModel plant_;
  int lead_order_;
  double rolloff_hz_, lead_;
  std::vector<double> numerator_, denominator_;
  TransferFunctionStage filter_;
};

// The one rule for ATS coefficients, checked by the block and by the config reader: each bound
// finite with min < max, each initial value inside its bounds, a0_bounds.min > 0. Throws
// std::invalid_argument opening with `label`.
void check_ats_coefficients(const AtsParameters& p, const std::string& label);

// The one rule for an adaptive correction's start, checked by the block and by the config
// reader: each coefficient starts at the identity (a0 = 1, a1 = a2 = 0) and its bounds are finite,
// min < max, and contain it. Throws std::invalid_argument opening with `label`.
void require_identity_start(const AtsParameters& p, const std::string& label);

// The correction's parameters when the config leaves them out: window 1 s, the identity
// (1, 0, 0), bounds a0 [0.5, 2], a1 [-0.05, 0.05] s, a2 [-1e-3, 1e-3] s^2, no filter.
AtsParameters adaptive_correction_defaults();

// The identity-started ATS correction in front of a ModelBasedInverse (equation above).
class AdaptedModelBasedInverse final : public Compensator {
 public:
  // @pre `correction` starts at the identity (a0 = 1, a1 = a2 = 0) and its bounds contain it;
  // throws std::invalid_argument naming the coefficient otherwise. The inverse's and the
  // correction's own preconditions hold (their constructors throw; the correction's messages
  // open with `label`).
  AdaptedModelBasedInverse(ModelBasedInverse inverse, const AtsParameters& correction, double dt,
                           const std::string& label = "adaptive correction");
  double step(const CompensatorInput& in) override;
  void reset() override;
  std::unique_ptr<Compensator> clone() const override;
  std::string describe() const override;
  // The feedforward's lead; the correction adds a1 (s) on top, which adapts.
  double nominal_lead() const override { return inverse_.nominal_lead(); }
  const ModelBasedInverse& inverse() const { return inverse_; }
  const AdaptiveTimeSeries& correction() const { return correction_; }
  Linearity linearity() const override { return correction_.linearity(); }
  std::complex<double> frequency_response(double omega) const override;
  LinearBlock state_space() const override;

 private:
  AdaptiveTimeSeries correction_;
  ModelBasedInverse inverse_;
};

// Roots of a polynomial (companion-matrix eigenvalues). Leading zeros are ignored.
std::vector<std::complex<double>> polynomial_roots(const std::vector<double>& coefficients);

}  // namespace rths::core
