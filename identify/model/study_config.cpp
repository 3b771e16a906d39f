#include "identify/model/study_config.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rths::identify {
namespace {

std::string absolute_from(const std::filesystem::path& base_dir, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return std::filesystem::absolute(base_dir / path).lexically_normal().string();
}

void absolute_traces(google::protobuf::RepeatedPtrField<config::DelayStage>& stages,
                     const std::filesystem::path& base_dir) {
  for (auto& stage : stages) {
    if (stage.has_trace()) {
      stage.mutable_trace()->set_path(absolute_from(base_dir, stage.trace().path()));
    }
  }
}

// The fitted effects a storey model has no place for, each with the reason; those a force stage
// holds (add_force_stages) say which.
void note_left_out_specimen_effects(const ChannelModel& specimen,
                                    std::vector<std::string>& left_out) {
  for (Effect e : specimen.effects) {
    switch (e) {
      case Effect::kDamping:
        left_out.push_back(effect_name(e) +
                           ": a velocity force beside the storey model (a viscous_force stage "
                           "holds it: add_force_stages)");
        break;
      case Effect::kCoulomb:
        left_out.push_back(effect_name(e) +
                           ": a friction force beside the storey model (a friction_force stage "
                           "holds it: add_force_stages)");
        break;
      case Effect::kInertia:
        left_out.push_back(effect_name(e) +
                           ": the specimen's own mass beside the storey model (an inertia_force "
                           "stage holds it: add_force_stages)");
        break;
      case Effect::kDelay:
        left_out.push_back(effect_name(e) +
                           ": the load cell's channel late (a force_delay stage holds it: "
                           "add_force_stages)");
        break;
      case Effect::kOffsetDrift:
        left_out.push_back(effect_name(e) +
                           ": the load cell's offset drift (a sensor_drift stage holds it: "
                           "add_force_stages)");
        break;
      case Effect::kCubicStiffness:
      case Effect::kTimeVaryingStiffness:
        left_out.push_back(effect_name(e) + ": no place in a storey model, left out");
        break;
      default: break;
    }
  }
}

// The actuator's linear stages after its shift (first order, second order), and what the study
// cannot hold of the rest in `out.left_out` (the rig's own effects are held `with_rig`).
void add_linear_stages(const ChannelModel& actuator, const SignalScales& scales, bool with_rig,
                       ActuatorCase& out) {
  const auto value = [&](std::optional<Effect> e, const char* param) {
    return actuator.param(e, param, scales);
  };
  for (Effect e : actuator.effects) {
    switch (e) {
      case Effect::kFirstOrder: {
        const double t = value(e, "time_constant").value_or(0.0);
        if (t > 0.0) out.study_case.add_delay()->mutable_first_order()->set_time_constant(t);
        break;
      }
      case Effect::kSecondOrder: {
        const double wn = value(e, "natural_frequency").value_or(0.0);
        const double zeta = value(e, "damping_ratio").value_or(0.0);
        if (!(wn > 0.0) || !(zeta > 0.0)) break;
        auto* tf = out.study_case.add_delay()->mutable_transfer_function();
        tf->add_numerator(wn * wn);
        for (double c : {1.0, 2.0 * zeta * wn, wn * wn}) tf->add_denominator(c);
        break;
      }
      case Effect::kTimeVaryingDelay:
        out.left_out.push_back("time-varying delay: its mean is used");
        break;
      case Effect::kTimeVaryingGain:
        out.left_out.push_back("time-varying gain: its mean is used");
        break;
      case Effect::kOffsetDrift:
      case Effect::kBacklash:
      case Effect::kVelocitySaturation:
      case Effect::kStrokeLimit:
        if (!with_rig) out.left_out.push_back(effect_name(e) + ": lab-scale effect, left out");
        break;
      default: break;
    }
  }
}

// Backlash, velocity limit and stroke limit in the model's order, then the displacement sensor's
// drift.
void add_rig_stages(const ChannelModel& actuator, const SignalScales& scales, const RigRecord& rig,
                    config::Case& study_case) {
  const auto value = [&](Effect e, const char* param) {
    return actuator.param(e, param, scales).value_or(0.0);
  };
  if (actuator.has(Effect::kBacklash))
    study_case.add_delay()->mutable_backlash()->set_width(
        std::abs(value(Effect::kBacklash, "width")));
  if (actuator.has(Effect::kVelocitySaturation))
    study_case.add_delay()->mutable_velocity_limit()->set_max_velocity(
        std::abs(value(Effect::kVelocitySaturation, "max_velocity")));
  if (actuator.has(Effect::kStrokeLimit))
    study_case.add_delay()->mutable_stroke_limit()->set_stroke(
        std::abs(value(Effect::kStrokeLimit, "stroke")));
  if (actuator.has(Effect::kOffsetDrift)) {
    const auto [offset, rate] = drift_in_time(value(Effect::kOffsetDrift, "offset"),
                                              value(Effect::kOffsetDrift, "drift"), rig);
    auto* sensor = study_case.add_delay()->mutable_sensor_drift();
    sensor->set_displacement_offset(offset);
    sensor->set_displacement_drift(rate);
  }
}

}  // namespace

std::pair<double, double> drift_in_time(double offset, double drift, const RigRecord& rig) {
  const double rate = drift / rig.duration;
  return {offset - rate * (rig.start + 0.5 * rig.duration), rate};
}

ActuatorCase actuator_case(const ChannelModel& actuator, const SignalScales& scales,
                           const std::string& name, const std::optional<RigRecord>& rig) {
  if (actuator.channel != Channel::kMeasured) {
    throw std::invalid_argument("actuator_case: needs the model of channel 'measured', got '" +
                                channel_name(actuator.channel) + "'");
  }
  ActuatorCase out;
  out.study_case.set_name(name);
  double delay = actuator.param(Effect::kDelay, "delay", scales).value_or(0.0);
  if (delay < 0.0) {
    out.left_out.push_back("negative delay (lead) of " + std::to_string(delay) + " s, used as 0");
    delay = 0.0;
  }
  const double gain = actuator.param(std::nullopt, "gain", scales).value_or(1.0);
  auto* shift = out.study_case.add_delay();
  shift->mutable_shift()->set_delay(delay);
  if (gain != 1.0 && !rig) shift->set_amplitude_gain(gain);
  add_linear_stages(actuator, scales, rig.has_value(), out);
  if (!rig) return out;
  add_rig_stages(actuator, scales, *rig, out.study_case);
  auto& stages = *out.study_case.mutable_delay();
  for (int i = stages.size() - 1; i >= 0; --i) {
    if (stages[i].has_sensor_drift() || is_force_stage(stages[i])) continue;
    if (gain != 1.0) stages[i].set_amplitude_gain(gain);
    break;
  }
  return out;
}

namespace {

// The case's sensor_drift stage, appended when it has none.
config::DelayStage::SensorDrift& sensor_drift_stage(config::Case& study_case) {
  for (auto& stage : *study_case.mutable_delay())
    if (stage.has_sensor_drift()) return *stage.mutable_sensor_drift();
  return *study_case.add_delay()->mutable_sensor_drift();
}

}  // namespace

namespace {

// `stages` after every stage of the case that moves the specimen, before the sensor_drift stages
// that end it (if any), so that their force offset is read after the load cell's lag, as the
// fitted model adds it (model.h: the offset is not shifted).
void insert_force_stages(const std::vector<config::DelayStage>& stages, config::Case& study_case) {
  auto& delay = *study_case.mutable_delay();
  int at = delay.size();
  while (at > 0 && delay[at - 1].has_sensor_drift()) --at;
  google::protobuf::RepeatedPtrField<config::DelayStage> ordered;
  for (int i = 0; i <= delay.size(); ++i) {
    if (i == at)
      for (const auto& s : stages) *ordered.Add() = s;
    if (i < delay.size()) *ordered.Add() = delay[i];
  }
  delay.Swap(&ordered);
}

}  // namespace

bool is_force_stage(const config::DelayStage& stage) {
  return stage.has_viscous_force() || stage.has_friction_force() || stage.has_inertia_force() ||
         stage.has_force_delay();
}

void keep_declared_force_stages(const config::Case& declared, config::Case& study_case) {
  std::vector<config::DelayStage> stages;
  for (const auto& stage : declared.delay())
    if (is_force_stage(stage)) stages.push_back(stage);
  insert_force_stages(stages, study_case);
}

bool held_by_force_stages(Effect effect) {
  switch (effect) {
    case Effect::kDamping:
    case Effect::kCoulomb:
    case Effect::kInertia:
    case Effect::kDelay:
    case Effect::kOffsetDrift: return true;
    default: return false;
  }
}

void add_force_stages(const ChannelModel& specimen, const SignalScales& scales,
                      const RigRecord& rig, config::Case& study_case,
                      const std::vector<Effect>& held) {
  const auto wanted = [&](Effect e) {
    return specimen.has(e) && std::find(held.begin(), held.end(), e) == held.end();
  };
  const auto value = [&](Effect e, const char* param) {
    return specimen.param(e, param, scales).value_or(0.0);
  };
  std::vector<config::DelayStage> stages;
  if (wanted(Effect::kDamping))
    stages.emplace_back().mutable_viscous_force()->set_damping(
        std::max(0.0, value(Effect::kDamping, "damping")));
  if (wanted(Effect::kCoulomb)) {
    auto* friction = stages.emplace_back().mutable_friction_force();
    friction->set_friction_force(std::abs(value(Effect::kCoulomb, "friction_force")));
    friction->set_smoothing_velocity(std::abs(value(Effect::kCoulomb, "smoothing_velocity")));
  }
  if (wanted(Effect::kInertia))
    stages.emplace_back().mutable_inertia_force()->set_mass(
        std::max(0.0, value(Effect::kInertia, "mass")));
  if (wanted(Effect::kDelay))
    stages.emplace_back().mutable_force_delay()->set_delay(
        std::max(0.0, value(Effect::kDelay, "delay")));
  insert_force_stages(stages, study_case);
  if (!wanted(Effect::kOffsetDrift)) return;
  const auto [offset, rate] = drift_in_time(value(Effect::kOffsetDrift, "offset"),
                                            value(Effect::kOffsetDrift, "drift"), rig);
  config::DelayStage::SensorDrift& sensor = sensor_drift_stage(study_case);
  sensor.set_force_offset(offset);
  sensor.set_force_drift(rate);
}

void add_displacement_scale(double scale, config::Case& study_case) {
  if (scale != 1.0) sensor_drift_stage(study_case).set_displacement_scale(scale);
}

SpecimenModel specimen_model(const ChannelModel& specimen, const SignalScales& scales) {
  if (specimen.channel != Channel::kForce) {
    throw std::invalid_argument("specimen_model: needs the model of channel 'force', got '" +
                                channel_name(specimen.channel) + "'");
  }
  SpecimenModel out;
  const auto value = [&](Effect e, const char* param) {
    return specimen.param(e, param, scales).value_or(0.0);
  };
  const double k = value(Effect::kStiffness, "stiffness");
  std::ostringstream text;
  text.precision(6);
  if (specimen.has(Effect::kBoucWen)) {
    const double f_bw = value(Effect::kBoucWen, "hysteretic_force");
    const double d_y = value(Effect::kBoucWen, "yield_drift");
    out.initial_stiffness = k + f_bw / d_y;
    if (out.initial_stiffness > 0.0 && d_y > 0.0) {
      config::RestoringForce model;
      auto* bw = model.mutable_bouc_wen();
      bw->set_yield_displacement(d_y);
      bw->set_alpha(k / out.initial_stiffness);
      bw->set_n(1.0);
      bw->set_beta(0.5);
      out.restoring_force = model;
      text << "Bouc-Wen: k0 " << out.initial_stiffness << " N/m, yield displacement " << d_y
           << " m, alpha " << bw->alpha();
    }
    if (specimen.has(Effect::kElastoPlastic)) {
      out.left_out.push_back("elastoplastic: a storey model has one hysteresis, Bouc-Wen kept");
    }
  } else if (specimen.has(Effect::kElastoPlastic)) {
    const double k_p = value(Effect::kElastoPlastic, "plastic_stiffness");
    const double f_y = value(Effect::kElastoPlastic, "yield_force");
    out.initial_stiffness = k + k_p;
    if (k_p > 0.0 && f_y > 0.0) {
      config::RestoringForce model;
      auto* b = model.mutable_bilinear();
      b->set_yield_displacement(f_y / k_p);
      b->set_post_yield_ratio(k / out.initial_stiffness);
      out.restoring_force = model;
      text << "bilinear: k0 " << out.initial_stiffness << " N/m, yield displacement "
           << b->yield_displacement() << " m, post-yield ratio " << b->post_yield_ratio();
    }
  } else if (k > 0.0) {
    out.initial_stiffness = k;
    config::RestoringForce model;
    model.mutable_linear();
    out.restoring_force = model;
    text << "linear: k0 " << k << " N/m";
  }
  if (!out.restoring_force) text << "no displacement-dependent force: no storey model";
  note_left_out_specimen_effects(specimen, out.left_out);
  out.description = text.str();
  return out;
}

config::Study study_fragment(const std::optional<ActuatorCase>& actuator,
                             const std::optional<SpecimenModel>& specimen) {
  config::Study fragment;
  if (specimen && specimen->restoring_force) {
    *fragment.mutable_substructuring()->mutable_model() = *specimen->restoring_force;
  }
  if (actuator) *fragment.add_cases() = actuator->study_case;
  return fragment;
}

config::Study identified_study(const config::Study& base, const std::filesystem::path& base_dir,
                               const config::Study& fragment) {
  config::Study study = base;
  study.set_name((base.name().empty() ? std::string("study") : base.name()) + "_identified");
  study.mutable_output()->clear_directory();
  if (study.has_motion()) {
    study.mutable_motion()->set_path(absolute_from(base_dir, study.motion().path()));
  }
  for (auto& motion : *study.mutable_sweep()->mutable_motions()) {
    motion.set_path(absolute_from(base_dir, motion.path()));
  }
  if (study.structure().has_matrices()) {
    auto& m = *study.mutable_structure()->mutable_matrices();
    const auto absolute_file = [&](config::Matrix& matrix) {
      if (!matrix.file().empty()) matrix.set_file(absolute_from(base_dir, matrix.file()));
    };
    if (m.has_mass()) absolute_file(*m.mutable_mass());
    if (m.has_stiffness()) absolute_file(*m.mutable_stiffness());
    if (m.has_damping()) absolute_file(*m.mutable_damping());
    if (m.has_influence()) absolute_file(*m.mutable_influence());
  }
  for (auto& c : *study.mutable_cases()) absolute_traces(*c.mutable_delay(), base_dir);
  for (auto& node : *study.mutable_deployment()->mutable_nodes()) {
    absolute_traces(*node.mutable_receive_delay(), base_dir);
    absolute_traces(*node.mutable_send_delay(), base_dir);
  }
  if (fragment.has_substructuring() && fragment.substructuring().has_model()) {
    *study.mutable_substructuring()->mutable_model() = fragment.substructuring().model();
  }
  for (const auto& c : fragment.cases()) {
    for (const auto& existing : study.cases()) {
      if (existing.name() == c.name()) {
        throw std::invalid_argument("the study already has a case named '" + c.name() + "'");
      }
    }
    *study.add_cases() = c;
  }
  return study;
}

}  // namespace rths::identify
