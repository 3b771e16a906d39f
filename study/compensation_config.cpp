#include "study/compensation_config.h"

#include <cmath>
#include <stdexcept>

#include "core/number_text.h"
#include "core/precondition.h"

namespace rths::study {
namespace {

core::AtsParameters correction_parameters(const config::Compensation::AdaptiveCorrection& c) {
  core::AtsParameters p = core::adaptive_correction_defaults();
  p.window = c.window();
  if (c.has_a0_bounds()) p.a0_bounds = {c.a0_bounds().min(), c.a0_bounds().max()};
  if (c.has_a1_bounds()) p.a1_bounds = {c.a1_bounds().min(), c.a1_bounds().max()};
  if (c.has_a2_bounds()) p.a2_bounds = {c.a2_bounds().min(), c.a2_bounds().max()};
  p.derivative_cutoff = c.derivative_cutoff();
  return p;
}

core::AtsParameters ats_parameters(const config::Compensation::AdaptiveTimeSeries& c) {
  core::AtsParameters p;
  p.window = c.window();
  p.a0 = c.initial_a0() == 0.0 ? 1.0 : c.initial_a0();
  p.a1 = c.initial_a1();
  p.a2 = c.initial_a2();
  if (c.has_a0_bounds()) p.a0_bounds = {c.a0_bounds().min(), c.a0_bounds().max()};
  if (c.has_a1_bounds()) p.a1_bounds = {c.a1_bounds().min(), c.a1_bounds().max()};
  if (c.has_a2_bounds()) p.a2_bounds = {c.a2_bounds().min(), c.a2_bounds().max()};
  p.derivative_cutoff = c.derivative_cutoff();
  return p;
}

}  // namespace

core::PlantModel plant_from_stages(
    const google::protobuf::RepeatedPtrField<config::DelayStage>& stages,
    const std::string& where) {
  using K = config::DelayStage::KindCase;
  core::PlantModel plant;
  core::require(!stages.empty(),
                where +
                    " is empty: a model-based compensator needs the actuator model "
                    "(e.g. from `rths identify --design-compensator`)");
  for (int i = 0; i < stages.size(); ++i) {
    const config::DelayStage& stage = stages[i];
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (stage.amplitude_gain() != 0.0) plant.gain *= stage.amplitude_gain();
    switch (stage.kind_case()) {
      case K::kShift:
        core::require(stage.shift().delay() >= 0.0, at + ".shift.delay must be >= 0 s");
        plant.delay += stage.shift().delay();
        break;
      case K::kFirstOrder:
        core::require(stage.first_order().time_constant() > 0.0,
                      at + ".first_order.time_constant must be > 0 s");
        plant.append({1.0}, {stage.first_order().time_constant(), 1.0});
        break;
      case K::kTransferFunction: {
        const auto& tf = stage.transfer_function();
        core::require(!tf.numerator().empty() && !tf.denominator().empty(),
                      at + ".transfer_function needs a numerator and a denominator");
        plant.append({tf.numerator().begin(), tf.numerator().end()},
                     {tf.denominator().begin(), tf.denominator().end()});
        break;
      }
      case K::kBenchmark: {
        const core::ContinuousTransferFunction benchmark =
            core::benchmark_actuator_transfer_function();
        plant.append(benchmark.numerator, benchmark.denominator);
        break;
      }
      default:
        core::fail(at +
                   ": only shift, first_order, transfer_function and benchmark stages describe an "
                   "invertible actuator model");
    }
  }
  return plant;
}

void validate_compensation(const config::Compensation& c, const std::string& where) {
  using K = config::Compensation::KindCase;
  switch (c.kind_case()) {
    case K::kPolynomial: {
      const auto& p = c.polynomial();
      core::require(
          p.order() >= 1 && p.order() <= 3,
          where + ".polynomial.order must be 1, 2 or 3, got " + std::to_string(p.order()));
      core::require(
          p.lead() > 0.0 && p.lead() <= 1.0,
          where + ".polynomial.lead must be in (0, 1] s, got " + core::format_number(p.lead()));
      core::require(
          p.spacing() >= 0.0 && std::isfinite(p.spacing()),
          where + ".polynomial.spacing must be >= 0 s, got " + core::format_number(p.spacing()));
      break;
    }
    case K::kAdaptiveTimeSeries: {
      const auto& a = c.adaptive_time_series();
      core::require(a.window() > 0.0 && std::isfinite(a.window()),
                    where + ".adaptive_time_series.window must be > 0 s, got " +
                        core::format_number(a.window()));
      // Bounds and initial values do not depend on dt: checked here as the block checks them.
      core::require(a.derivative_cutoff() >= 0.0 && std::isfinite(a.derivative_cutoff()),
                    where + ".adaptive_time_series.derivative_cutoff must be >= 0 Hz");
      core::check_ats_coefficients(ats_parameters(a), where + ".adaptive_time_series");
      break;
    }
    case K::kModelBased: {
      const auto& m = c.model_based();
      core::require(m.lead_order() >= 1 && m.lead_order() <= 3,
                    where + ".model_based.lead_order must be 1, 2 or 3, got " +
                        std::to_string(m.lead_order()));
      core::require(m.rolloff_frequency() > 0.0 && std::isfinite(m.rolloff_frequency()),
                    where + ".model_based.rolloff_frequency must be > 0 Hz, got " +
                        core::format_number(m.rolloff_frequency()));
      plant_from_stages(m.plant(), where + ".model_based.plant");
      if (m.has_adaptive_correction()) {
        const auto& a = m.adaptive_correction();
        const std::string at = where + ".model_based.adaptive_correction";
        core::require(a.window() > 0.0 && std::isfinite(a.window()),
                      at + ".window must be > 0 s, got " + core::format_number(a.window()));
        core::require(a.derivative_cutoff() >= 0.0 && std::isfinite(a.derivative_cutoff()),
                      at + ".derivative_cutoff must be >= 0 Hz, got " +
                          core::format_number(a.derivative_cutoff()));
        const core::AtsParameters correction = correction_parameters(a);
        core::require_identity_start(correction, at);
        core::check_ats_coefficients(correction, at);
      }
      break;
    }
    case K::KIND_NOT_SET:
      core::fail(where + " has no kind (polynomial, adaptive_time_series, model_based)");
  }
}

std::unique_ptr<core::Compensator> make_compensator(const config::Compensation& c, double dt,
                                                    const std::string& where) {
  validate_compensation(c, where);
  using K = config::Compensation::KindCase;
  switch (c.kind_case()) {
    case K::kPolynomial: {
      const auto& p = c.polynomial();
      int spacing = 1;
      if (p.spacing() > 0.0) {
        const double steps = p.spacing() / dt;
        spacing = static_cast<int>(std::llround(steps));
        core::require(spacing >= 1 && std::abs(steps - spacing) <= 1e-6 * steps,
                      where + ".polynomial.spacing " + core::format_number(p.spacing()) +
                          " s is not a whole number of steps of dt = " + core::format_number(dt) +
                          " s");
      }
      return std::make_unique<core::PolynomialExtrapolation>(p.order(), p.lead(), spacing, dt);
    }
    case K::kAdaptiveTimeSeries:
      return std::make_unique<core::AdaptiveTimeSeries>(ats_parameters(c.adaptive_time_series()),
                                                        dt, where + ".adaptive_time_series");
    case K::kModelBased: {
      const auto& m = c.model_based();
      core::ModelBasedInverse inverse(plant_from_stages(m.plant(), where + ".model_based.plant"),
                                      m.lead_order(), m.rolloff_frequency(), dt,
                                      where + ".model_based");
      if (!m.has_adaptive_correction())
        return std::make_unique<core::ModelBasedInverse>(std::move(inverse));
      return std::make_unique<core::AdaptedModelBasedInverse>(
          std::move(inverse), correction_parameters(m.adaptive_correction()), dt,
          where + ".model_based.adaptive_correction");
    }
    case K::KIND_NOT_SET: break;
  }
  core::fail(where + " has no kind (polynomial, adaptive_time_series, model_based)");
}

}  // namespace rths::study
