#include "identify/run/moving_parameter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/number_text.h"
#include "core/rig_effects.h"
#include "identify/fit/effect_parameters.h"
#include "identify/run/sensors.h"
#include "identify/run/unexplained.h"

namespace rths::identify {
namespace {

// The drift's name in its coefficients (model.h <prefix>_c1 ...), empty for a constant effect.
std::string drift_prefix(const std::string& effect) {
  if (effect == "time_varying_stiffness") return "stiffness";
  if (effect == "time_varying_gain") return "gain";
  if (effect == "time_varying_delay") return "delay";
  return "";
}

// Adds (v(t) - v) s x to the force read, x the displacement the stage passes (m).
class MovingStiffness final : public core::PassThroughStage {
 public:
  MovingStiffness(const MovingParameter& moving, double displacement_scale)
      : moving_(moving), scale_(displacement_scale) {}
  void reset() override { time_ = passed_ = 0.0; }
  std::unique_ptr<core::DelayStage> clone() const override {
    return std::make_unique<MovingStiffness>(*this);
  }
  std::string describe() const override { return "moving stiffness"; }
  double measure_force(double force) override {
    return force + (moving_.shape.value_at(time_) - moving_.constant) * scale_ * passed_;
  }

 protected:
  void observe(const core::CommandSample& in) override {
    time_ = in.time;
    passed_ = in.displacement;
  }

 private:
  MovingParameter moving_;
  double scale_ = 1.0;
  double time_ = 0.0, passed_ = 0.0;  // s, m: the last step's
};

// Multiplies the displacement by v(t) / v.
class MovingGain final : public core::DelayStage {
 public:
  explicit MovingGain(const MovingParameter& moving) : moving_(moving) {}
  void reset() override {}
  std::unique_ptr<core::DelayStage> clone() const override {
    return std::make_unique<MovingGain>(*this);
  }
  std::string describe() const override { return "moving gain"; }
  double nominal_delay() const override { return 0.0; }

 protected:
  double step_unscaled(const core::CommandSample& in) override {
    return in.displacement * moving_.shape.value_at(in.time) / moving_.constant;
  }

 private:
  MovingParameter moving_;
};

}  // namespace

std::optional<MovingParameter> moving_parameter(const ActuatorPath& path, Channel channel,
                                                const std::string& effect) {
  const std::string prefix = drift_prefix(effect);
  if (prefix.empty()) return std::nullopt;
  const EffectEstimate* estimate = path.estimate(channel, parse_effect(effect));
  if (!estimate || estimate->parameters.size() != kDriftTerms) return std::nullopt;
  MovingParameter out;
  out.actuator = path.actuator;
  out.channel = channel;
  out.part = part_of(effect, channel, path.actuator);
  out.effect = effect;
  out.unit = prefix == "stiffness" ? "N/m" : prefix == "gain" ? "" : "s";
  out.constant = prefix == "stiffness" ? path.fitted_stiffness
                 : prefix == "gain"    ? path.fitted_gain
                                       : path.fitted_delay;
  const ChannelSignals& signals = identified_signals(path.id, channel);
  const double start = signals.time.front(), duration = signals.time.back() - start;
  std::vector<double> time(kMovingWindows), value(kMovingWindows);
  for (std::size_t w = 0; w < kMovingWindows; ++w) {
    // s + 1/2 of the window's centre (model.h: D(s; c) = sum c_k cos(pi k (s + 1/2))).
    const double place = (static_cast<double>(w) + 0.5) / static_cast<double>(kMovingWindows);
    double drift = 0.0;
    for (std::size_t k = 0; k < kDriftTerms; ++k)
      drift += estimate->parameters[k].value *
               std::cos(std::numbers::pi * static_cast<double>(k + 1) * place);
    time[w] = start + place * duration;
    value[w] = prefix == "gain" ? out.constant * (1.0 + drift) : out.constant + drift;
  }
  out.shape = fit_shape(time, value);
  return out;
}

std::vector<MovingParameter> moving_parameters(const ActuatorPath& path) {
  std::vector<MovingParameter> out;
  for (Channel channel : {Channel::kMeasured, Channel::kForce})
    for (const std::string& effect :
         channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared)
      if (auto moving = moving_parameter(path, channel, effect)) out.push_back(std::move(*moving));
  return out;
}

std::optional<MovingParameter> described_moving(const Unexplained& described,
                                                const ActuatorPath& path, bool specimen_rerun) {
  const auto& trend = described.description.time_varying;
  const bool force = described.channel == Channel::kForce;
  const std::string part = (force ? "specimen " : "actuator ") + std::to_string(path.actuator);
  // A trend of the lead on the model (of_rate) moves no stiffness or gain.
  if (!trend || trend->of_rate || described.part != part) return std::nullopt;
  MovingParameter out;
  out.actuator = path.actuator;
  out.channel = described.channel;
  out.part = part;
  out.effect = force ? "time_varying_stiffness" : "time_varying_gain";
  out.unit = force ? "N/m" : "";
  out.constant = !force           ? path.fitted_gain
                 : specimen_rerun ? path.fitted_stiffness
                                  : path.declared_stiffness;
  if (!(out.constant > 0.0)) return std::nullopt;
  // v (1 + rho) of the ratio's shape: the same shape, its levels scaled.
  out.shape = trend->shape;
  out.shape.start = out.constant * (1.0 + trend->shape.start);
  out.shape.end = out.constant * (1.0 + trend->shape.end);
  return out;
}

std::unique_ptr<core::DelayStage> moving_stage(const MovingParameter& moving,
                                               double displacement_scale) {
  if (moving.effect == "time_varying_stiffness")
    return std::make_unique<MovingStiffness>(moving, displacement_scale);
  if (moving.effect == "time_varying_gain" && moving.constant != 0.0)
    return std::make_unique<MovingGain>(moving);
  return nullptr;
}

bool hold_moving_delay(const MovingParameter& moving, config::Case& study_case) {
  if (moving.effect != "time_varying_delay") return false;
  for (config::DelayStage& stage : *study_case.mutable_delay()) {
    if (!stage.has_shift()) continue;
    config::DelayStage::Trace& trace = *stage.mutable_trace();  // clears the shift
    trace.set_path("identified: " + moving.part + " time_varying_delay (" +
                   shape_name(moving.shape.shape) + ")");
    // The record: half a window before the first window's centre to half one after the last.
    const double half_window =
        0.5 * (moving.shape.last - moving.shape.first) / static_cast<double>(kMovingWindows - 1);
    const double first = moving.shape.first - half_window, last = moving.shape.last + half_window;
    for (std::size_t i = 0; i < kTraceSamples; ++i) {
      const double t =
          first + (last - first) * static_cast<double>(i) / static_cast<double>(kTraceSamples - 1);
      trace.add_time(t);
      trace.add_delay(std::max(0.0, moving.shape.value_at(t)));
    }
    return true;
  }
  return false;
}

std::string moving_not_written(const MovingParameter& moving) {
  if (moving.effect == "time_varying_delay") return "";
  return moving.part + ": " + moving.effect + ": a study holds no time-varying " +
         (moving.effect == "time_varying_gain" ? "gain" : "stiffness") +
         ": written as its constant " + core::format_number(moving.constant) + " " + moving.unit +
         " (the re-run held it moving, " + shape_name(moving.shape.shape) + " " +
         core::format_number(moving.shape.start) + " -> " + core::format_number(moving.shape.end) +
         ")";
}

std::string constant_change_of(const std::string& moving_effect) {
  if (moving_effect == "time_varying_stiffness") return "stiffness change";
  if (moving_effect == "time_varying_gain") return "gain error";
  if (moving_effect == "time_varying_delay") return "delay change";
  return "";
}

double declared_constant(const ActuatorPath& path, const std::string& moving_effect) {
  if (moving_effect == "time_varying_stiffness") return path.declared_stiffness;
  if (moving_effect == "time_varying_gain") return path.declared_gain;
  return path.declared_delay;
}

void merge_constant_changes(ActuatorPath& path) {
  for (auto* named : {&path.undeclared, &path.specimen_undeclared}) {
    std::vector<std::string> merged;
    for (const std::string& effect : *named) {
      const std::string constant = constant_change_of(effect);
      if (!constant.empty() && std::find(named->begin(), named->end(), constant) != named->end())
        merged.push_back(constant);
    }
    for (const std::string& constant : merged) {
      std::erase(*named, constant);
      path.merged_constants.push_back(constant);
    }
  }
}

void restore_merged_constant(ActuatorPath& path, std::vector<std::string>& named,
                             const std::string& rejected) {
  const std::string constant = constant_change_of(rejected);
  const auto at = std::find(path.merged_constants.begin(), path.merged_constants.end(), constant);
  if (constant.empty() || at == path.merged_constants.end()) return;
  path.merged_constants.erase(at);
  named.push_back(constant);
}

}  // namespace rths::identify
