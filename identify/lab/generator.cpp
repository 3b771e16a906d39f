#include "identify/lab/generator.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/delay.h"
#include "core/restoring_force.h"

namespace rths::identify {
namespace {

std::vector<double> chirp(const GeneratorSpec& spec, std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * spec.dt;
    const double phase = 2.0 * std::numbers::pi *
                         (spec.chirp_start * t +
                          (spec.chirp_end - spec.chirp_start) * t * t / (2.0 * spec.duration));
    // Half-second cosine ramps keep the start and end free of steps.
    const double ramp = std::min({1.0, t / 0.5, (spec.duration - t) / 0.5});
    u[i] = spec.amplitude * std::max(0.0, ramp) * std::sin(phase);
  }
  return u;
}

std::vector<double> earthquake_like(const GeneratorSpec& spec, std::size_t n) {
  std::mt19937_64 rng(spec.seed * 7919 + 17);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double wn = 2.0 * std::numbers::pi * spec.corner_frequency;
  core::TransferFunctionStage low_pass({wn * wn}, {1.0, 2.0 * 0.6 * wn, wn * wn}, spec.dt);
  const double wh = 2.0 * std::numbers::pi * 0.2;
  core::TransferFunctionStage high_pass({1.0, 0.0}, {1.0, wh}, spec.dt);
  std::vector<double> u(n);
  double peak = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * spec.dt;
    const double x = low_pass.step({t, normal(rng), 0.0});
    const double y = high_pass.step({t, x, 0.0});
    const double rise = 0.1 * spec.duration, decay_start = 0.6 * spec.duration;
    double envelope = t < rise ? t / rise : 1.0;
    if (t > decay_start)
      envelope = std::exp(-3.0 * (t - decay_start) / (spec.duration - decay_start));
    u[i] = y * envelope;
    peak = std::max(peak, std::abs(u[i]));
  }
  for (double& v : u) v *= peak > 0.0 ? spec.amplitude / peak : 0.0;
  return u;
}

std::vector<double> derivative(const std::vector<double>& x, double dt) {
  std::vector<double> d(x.size(), 0.0);
  for (std::size_t i = 1; i + 1 < x.size(); ++i) d[i] = (x[i + 1] - x[i - 1]) / (2.0 * dt);
  if (x.size() > 1) {
    d.front() = (x[1] - x[0]) / dt;
    d.back() = (x[x.size() - 1] - x[x.size() - 2]) / dt;
  }
  return d;
}

}  // namespace

namespace {

// The actuator's declared path: a (possibly drifting) delay with gain, then the optional first-
// and second-order lags.
core::DelayChain actuator_chain(const GeneratorSpec& spec, const std::vector<double>& time) {
  core::DelayChain chain;
  if (spec.delay_drift != 0.0) {
    if (std::abs(spec.delay_drift) > spec.delay) {
      throw std::invalid_argument("generator: delay_drift must not exceed delay (a delay >= 0)");
    }
    core::DelayTrace trace;
    for (const double t : time) {
      trace.time.push_back(t);
      trace.delay.push_back(spec.delay + spec.delay_drift *
                                             std::sin(2.0 * std::numbers::pi * t / spec.duration));
    }
    auto shift = std::make_unique<core::TraceShift>(std::move(trace), spec.dt);
    shift->set_gain(spec.gain);
    chain.add(std::move(shift));
  } else {
    auto shift = std::make_unique<core::TimeShift>(spec.delay, spec.dt);
    shift->set_gain(spec.gain);
    chain.add(std::move(shift));
  }
  if (spec.first_order_time_constant > 0.0) {
    chain.add(std::make_unique<core::FirstOrderActuator>(spec.first_order_time_constant, spec.dt));
  }
  if (spec.second_order_frequency > 0.0) {
    const double wn = 2.0 * std::numbers::pi * spec.second_order_frequency;
    chain.add(std::make_unique<core::TransferFunctionStage>(
        std::vector<double>{wn * wn},
        std::vector<double>{1.0, 2.0 * spec.second_order_damping * wn, wn * wn}, spec.dt));
  }
  return chain;
}

// The displacement the actuator reaches (m): the chain, then backlash, velocity saturation,
// drifting gain, offset and drift.
std::vector<double> realised_displacement(const GeneratorSpec& spec, const MeasuredData& data) {
  const std::size_t n = data.time.size();
  const std::vector<double> command_velocity = derivative(data.command, spec.dt);
  core::DelayChain chain = actuator_chain(spec, data.time);
  std::vector<double> realised(n);
  double play = 0.0, saturated = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    double x = chain.step({data.time[i], data.command[i], command_velocity[i]});
    if (spec.backlash_width > 0.0) {
      play = std::clamp(play, x - 0.5 * spec.backlash_width, x + 0.5 * spec.backlash_width);
      x = play;
    }
    if (spec.max_velocity > 0.0) {
      const double max_step = spec.max_velocity * spec.dt;
      saturated += std::clamp(x - saturated, -max_step, max_step);
      x = saturated;
    }
    const double s = (data.time[i] - 0.5 * data.time.back()) / data.time.back();
    const double drifting_gain =
        1.0 + spec.gain_drift * std::sin(2.0 * std::numbers::pi * data.time[i] / spec.duration);
    realised[i] = drifting_gain * x + spec.offset + spec.drift * s;
  }
  return realised;
}

// The specimen's force (N) on the realised displacement, and both channels with their noise.
void measure_specimen(const GeneratorSpec& spec, const std::vector<double>& realised,
                      MeasuredData& data) {
  const std::size_t n = realised.size();
  const auto velocity = derivative(realised, spec.dt);
  const auto acceleration = derivative(velocity, spec.dt);
  std::unique_ptr<core::RestoringForceModel> spring;
  if (spec.bouc_wen_yield > 0.0) {
    spring = std::make_unique<core::BoucWen>(spec.stiffness, spec.bouc_wen_yield,
                                             spec.bouc_wen_alpha, 1.0, 0.5);
  } else {
    spring = std::make_unique<core::LinearSpring>(spec.stiffness);
  }
  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  data.measured.resize(n);
  data.force.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = realised[i], v = velocity[i];
    double f = spring->step(d) + spec.damping * v + spec.cubic_stiffness * d * d * d +
               spec.mass * acceleration[i] + spec.force_offset +
               spec.stiffness_drift * spec.stiffness *
                   std::sin(2.0 * std::numbers::pi * data.time[i] / spec.duration) * d;
    if (spec.coulomb_force != 0.0) f += spec.coulomb_force * std::tanh(v / spec.coulomb_velocity);
    data.measured[i] = d + spec.displacement_noise * normal(rng);
    data.force[i] = f + spec.force_noise * normal(rng);
  }
}

}  // namespace

MeasuredData generate_measured(const GeneratorSpec& spec) {
  if (!(spec.duration > 0.0)) throw std::invalid_argument("generator: duration must be > 0");
  if (!(spec.dt > 0.0)) throw std::invalid_argument("generator: dt must be > 0");
  if (!(spec.amplitude > 0.0)) throw std::invalid_argument("generator: amplitude must be > 0");
  const auto n = static_cast<std::size_t>(std::floor(spec.duration / spec.dt)) + 1;
  if (n < kDefaultMinSamples) {
    throw std::invalid_argument("generator: duration / dt gives fewer than " +
                                std::to_string(kDefaultMinSamples) + " samples");
  }
  MeasuredData data;
  data.source = "generator";
  data.dt = spec.dt;
  data.time.resize(n);
  for (std::size_t i = 0; i < n; ++i) data.time[i] = static_cast<double>(i) * spec.dt;
  data.command =
      spec.command == GeneratorSpec::Command::kChirp ? chirp(spec, n) : earthquake_like(spec, n);
  measure_specimen(spec, realised_displacement(spec, data), data);
  validate(data, kDefaultMinSamples);
  return data;
}

}  // namespace rths::identify
