#include "study/tracking_config.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/number_text.h"

namespace rths::study {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw std::invalid_argument(field + ": " + problem);
}

std::vector<double> values(const google::protobuf::RepeatedField<double>& field) {
  return {field.begin(), field.end()};
}

// kp + ki / s + kd s / (tf s + 1) over the common denominator s (tf s + 1).
core::ContinuousTransferFunction pid_transfer_function(
    const config::DelayStage::LinearFilter::Pid& pid, const std::string& field) {
  if (pid.kd() != 0.0 && !(pid.derivative_filter() > 0))
    fail(field + ".pid.derivative_filter", "must be > 0 s when kd is set (a proper derivative)");
  const double tf = pid.derivative_filter();
  if (tf == 0.0) return {{pid.kp(), pid.ki()}, {1.0, 0.0}};
  return {{pid.kp() * tf + pid.kd(), pid.kp() + pid.ki() * tf, pid.ki()}, {tf, 1.0, 0.0}};
}

// The transfer function of the state space `spec` (core::state_space_transfer_function).
core::ContinuousTransferFunction state_space_of(
    const config::DelayStage::LinearFilter::StateSpace& spec, const std::string& field) {
  const int n = spec.states();
  const auto size = static_cast<std::size_t>(n);
  if (n < 1 || n > 16) fail(field + ".state_space.states", std::to_string(n) + " is outside 1..16");
  if (static_cast<std::size_t>(spec.a_size()) != size * size ||
      static_cast<std::size_t>(spec.b_size()) != size ||
      static_cast<std::size_t>(spec.c_size()) != size)
    fail(field + ".state_space",
         "a needs states^2 = " + std::to_string(n * n) + " values (row-major), b and c " +
             std::to_string(n) + "; got " + std::to_string(spec.a_size()) + ", " +
             std::to_string(spec.b_size()) + ", " + std::to_string(spec.c_size()));
  core::Mat a(n, n);
  core::Vec b(n), c(n);
  for (int i = 0; i < n; ++i) {
    b[i] = spec.b(i);
    c[i] = spec.c(i);
    for (int j = 0; j < n; ++j) a(i, j) = spec.a(i * n + j);
  }
  if (!a.allFinite() || !b.allFinite() || !c.allFinite() || !std::isfinite(spec.d()))
    fail(field + ".state_space", "holds a value that is not finite");
  return core::state_space_transfer_function(a, b, c, spec.d());
}

}  // namespace

core::DiscreteFilter make_filter(const config::DelayStage::LinearFilter& spec, double h,
                                 const std::string& field) {
  using K = config::DelayStage::LinearFilter::KindCase;
  try {
    switch (spec.kind_case()) {
      case K::kContinuous: {
        const core::DiscreteCoefficients d = core::tustin(
            values(spec.continuous().numerator()), values(spec.continuous().denominator()), h);
        return core::DiscreteFilter(d.b, d.a);
      }
      case K::kDiscrete:
        return core::DiscreteFilter(values(spec.discrete().numerator()),
                                    values(spec.discrete().denominator()));
      case K::kStateSpace: {
        // A polynomial in z, highest power first, is b(z^-1) in ascending powers: the same list.
        const core::ContinuousTransferFunction tf = state_space_of(spec.state_space(), field);
        if (spec.state_space().discrete())
          return core::DiscreteFilter(tf.numerator, tf.denominator);
        const core::DiscreteCoefficients d = core::tustin(tf.numerator, tf.denominator, h);
        return core::DiscreteFilter(d.b, d.a);
      }
      case K::kPid: {
        const core::ContinuousTransferFunction tf = pid_transfer_function(spec.pid(), field);
        const core::DiscreteCoefficients d = core::tustin(tf.numerator, tf.denominator, h);
        return core::DiscreteFilter(d.b, d.a);
      }
      case K::kPhaseLead: {
        const auto& lead = spec.phase_lead();
        if (!(lead.zero() > 0 && lead.pole() > 0 && lead.gain() != 0))
          fail(field + ".phase_lead", "zero and pole must be > 0 rad/s and the gain non-zero");
        const core::DiscreteCoefficients d =
            core::tustin({lead.gain(), lead.gain() * lead.zero()}, {1.0, lead.pole()}, h);
        return core::DiscreteFilter(d.b, d.a);
      }
      case K::KIND_NOT_SET: break;
    }
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    if (what.rfind(field, 0) == 0) throw;
    fail(field, what);
  }
  fail(field, "has no kind (continuous, discrete, pid, phase_lead or state_space)");
}

core::BenchmarkPlantParameters benchmark_plant_parameters(
    const config::DelayStage::BenchmarkPlant& spec) {
  const auto or_nominal = [](double value, double nominal) {
    return value != 0.0 ? value : nominal;
  };
  core::BenchmarkPlantParameters p;
  p.a1_beta0 = or_nominal(spec.a1_beta0(), 2.1283e13);
  p.a2 = or_nominal(spec.a2(), 4.2297e6);
  p.a3 = or_nominal(spec.a3(), 3.3);
  p.beta1 = or_nominal(spec.beta1(), 425.0);
  p.beta2 = or_nominal(spec.beta2(), 9.9976e4);
  p.gain = or_nominal(spec.gain(), 1.0261);
  // Given, they must be physical: an explicit 0 is refused, not run as the nominal value.
  if (spec.has_mass() && !(spec.mass() > 0))
    fail("benchmark_plant.mass",
         core::format_number(spec.mass()) + " kg must be > 0 (omit it for 29.13)");
  if (spec.has_stiffness() && !(spec.stiffness() > 0))
    fail("benchmark_plant.stiffness",
         core::format_number(spec.stiffness()) + " N/m must be > 0 (omit it for 1.19e6)");
  p.mass = spec.has_mass() ? spec.mass() : 29.13;
  p.stiffness = spec.has_stiffness() ? spec.stiffness() : 1.19e6;
  p.damping = or_nominal(spec.damping(), 2.0 * 0.0097 * std::sqrt(p.stiffness * p.mass));
  return p;
}

namespace {

core::ContinuousTransferFunction plant_of(const config::DelayStage::TrackingLoop& spec,
                                          const std::string& field) {
  if (spec.has_benchmark_plant())
    return core::benchmark_actuator_transfer_function(
        benchmark_plant_parameters(spec.benchmark_plant()));
  if (!spec.has_plant()) fail(field + ".plant", "is missing (plant or benchmark_plant)");
  return {values(spec.plant().numerator()), values(spec.plant().denominator())};
}

core::ZohPlant make_plant(const config::DelayStage::TrackingLoop& spec, double h,
                          const std::string& field) {
  const core::ContinuousTransferFunction tf = plant_of(spec, field);
  try {
    return core::ZohPlant(tf.numerator, tf.denominator, h);
  } catch (const std::invalid_argument& e) {
    fail(field + ".plant", e.what());
  }
}

}  // namespace

core::TrackingLoop make_tracking_loop(const config::DelayStage::TrackingLoop& spec, double h,
                                      const std::string& field) {
  core::TrackingLoopOptions options;
  if (spec.has_controller())
    options.controller = make_filter(spec.controller(), h, field + ".controller");
  if (spec.has_feedforward())
    options.feedforward = make_filter(spec.feedforward(), h, field + ".feedforward");
  options.converter = {spec.converter().range(), spec.converter().quantum()};
  options.displacement_noise_rms = spec.displacement_noise_rms();
  options.force_noise_rms = spec.force_noise_rms();
  options.force_delay_periods = spec.force_delay_periods();
  options.seed = spec.seed();
  options.plant_name = spec.has_benchmark_plant() ? "benchmark plant" : "plant";
  return core::TrackingLoop(make_plant(spec, h, field), options, h, field);
}

}  // namespace rths::study
