#include "identify/run/run_record.h"

#include "identify/fit/effect_parameters.h"
#include "identify/model/study_config.h"
#include "identify/run/moving_parameter.h"
#include "identify/run/noise_period.h"
#include "identify/run/plausibility.h"
#include "identify/run/residual_floor.h"
#include "identify/run/sensors.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "runtime/node/answer_sources.h"
#include "runtime/node/schema.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"
#include "study/study.h"
#include "study/study_inputs.h"

namespace rths::identify {
namespace {

constexpr double kDivergenceBound = 1.0e3;  // m, the coordinator's default bound

[[noreturn]] void bad(const std::filesystem::path& record, const std::string& entry,
                      const std::string& problem) {
  throw std::invalid_argument(record.string() + ": " + entry + ": " + problem);
}

runtime::RecordContents read_checked(const std::filesystem::path& record) {
  runtime::RecordContents contents;
  try {
    contents = runtime::read_record(record);
  } catch (const std::runtime_error& e) {
    bad(record, "record", e.what());
  }
  if (contents.lost_entries()) bad(record, "damaged entries", contents.loss_report());
  const runtime::RunHeader* header = contents.header();
  if (header == nullptr)
    bad(record, "entry 0", "no header: not a run record, or its start was lost");
  if (header->schema_version() != runtime::kSchemaVersion) {
    bad(record, "header",
        "schema version " + std::to_string(header->schema_version()) +
            ", this rths reads version " + std::to_string(runtime::kSchemaVersion));
  }
  return contents;
}

// Steps [0, end) whose response is finite and within the divergence bound.
std::size_t usable_steps(const core::SimulationResult& steps) {
  for (Eigen::Index k = 0; k < steps.displacement.rows(); ++k) {
    const auto row = steps.displacement.row(k);
    if (!row.allFinite() || row.cwiseAbs().maxCoeff() > kDivergenceBound) {
      return static_cast<std::size_t>(k);
    }
  }
  return static_cast<std::size_t>(steps.displacement.rows());
}

std::string held_note(const runtime::RecordContents& contents, const runtime::RunMeasurements& m,
                      std::size_t usable) {
  std::ostringstream out;
  const auto recorded = static_cast<std::size_t>(m.steps.displacement.rows());
  if (usable < recorded || (m.has_footer && m.footer.diverged())) {
    out << "diverged: identified up to step " << usable << " of " << recorded << " recorded";
  } else if (!m.has_footer || contents.truncated) {
    out << "truncated: " << recorded << " steps held, no footer"
        << (contents.truncated ? " (" + contents.warning + ")" : "");
  } else {
    out << "complete: " << recorded << " steps, " << m.footer.status();
  }
  return out.str();
}

DeclaredLink declared_link(const config::Deployment& deployment, int node_id) {
  DeclaredLink out;
  for (const auto& node : deployment.nodes()) {
    if (node.id() != node_id) continue;
    const auto& in = node.receive_lag();
    const auto& send = node.send_lag();
    out.round_trip = in.one_way_delay() + send.one_way_delay();
    out.jitter = std::hypot(in.jitter(), send.jitter());
    out.loss = 1.0 - (1.0 - in.loss()) * (1.0 - send.loss());
    for (const auto* net : {&in.network(), &send.network()}) {
      out.drift = out.drift || net->drift_rate() != 0.0;
      out.spikes = out.spikes || (net->spike_delay() != 0.0 && net->spike_every() > 0);
      out.drops = out.drops || net->drop_steps() > 0;
    }
  }
  return out;
}

// The clock offset of a link's hosts from its one-way stamps, named among the link's effects
// when it matters (clock_offset.h). The stamps cover the whole record (a diverged run's answers
// tell the clocks as well as the others).
void add_clock_offset(const runtime::LinkSeries& series, const config::Deployment& deployment,
                      NetworkPath& path) {
  double injected_down = 0.0, injected_up = 0.0;
  for (const auto& node : deployment.nodes()) {
    if (node.id() != path.node_id) continue;
    injected_down = node.receive_lag().one_way_delay();
    injected_up = node.send_lag().one_way_delay();
  }
  path.clock = clock_offset(series.one_way_down, series.one_way_up, injected_down, injected_up);
  if (path.clock && path.clock->named)
    path.effects.push_back({"clock offset", path.clock->detail, 0.0, 0.0, 0.0});
}

std::vector<NetworkPath> identify_links(const std::filesystem::path& record,
                                        const runtime::RunHeader& header,
                                        const runtime::RunMeasurements& m, double until) {
  std::vector<NetworkPath> out;
  for (int id : header.link_node_ids()) {
    const auto found = m.links.find(id);
    LinkAnswers answers;
    answers.node_id = id;
    if (found != m.links.end()) {
      const runtime::LinkSeries& s = found->second;
      for (std::size_t i = 0; i < s.time.size() && s.time[i] <= until; ++i) {
        answers.time.push_back(s.time[i]);
        answers.answered_step.push_back(s.answered_step[i]);
        if (i < s.answers.size()) answers.answers.push_back(s.answers[i]);
        answers.round_trip.push_back(s.round_trip[i]);
        answers.injected.push_back(s.injected[i]);
      }
    }
    if (answers.time.size() < 20) {
      bad(record, "link to node " + std::to_string(id),
          std::to_string(answers.time.size()) + " answers in the record, at least 20 are needed");
    }
    out.push_back(identify_network_path(answers, declared_link(header.study().deployment(), id),
                                        header.dt()));
    if (found != m.links.end())
      add_clock_offset(found->second, header.study().deployment(), out.back());
  }
  return out;
}

// As run_residual.cpp's: the record's case, else its first; nullptr for a study without cases.
const config::Case* run_case(const config::Study& study, const std::string& name) {
  if (study.cases().empty()) return nullptr;
  const config::Case* named = study::case_named(study, name);
  return named ? named : &study.cases(0);
}

// The declared actuator (run_record.h): the case's stages, then the emulators' own receive
// stages, as effects with the config's values as initial values.
struct DeclaredActuator {
  std::vector<Effect> effects;
  std::vector<ParamDeclaration> parameters;
  std::vector<std::string> names;
  double gain = 1.0;
  // The declared pure delay (s): the first shift stage's, or 0 when no stage of any kind is
  // declared (a command then reaches the rig at once, so a fitted lag is a finding, "delay
  // change"); absent when the declared stages hold no shift (a tracking loop, a first-order lag:
  // their lag is the stage's, and one the search adds is its own effect).
  std::optional<double> delay;
  std::size_t stages = 0;  // declared, of any kind
  // RMS (m, N) of a tracking loop's sensor noise with its converter's quantisation (sensors.h).
  double displacement_noise = 0.0, force_noise = 0.0;
};

// A tracking loop's declared sensor noise: each channel's noise with the converter's
// quantisation q / sqrt(12) (the loop's converter is on the displacement; the load cell's
// noise is its own).
void declare_noise(const config::DelayStage::TrackingLoop& loop, DeclaredActuator& out) {
  const double q = loop.converter().quantum();
  out.displacement_noise = std::hypot(loop.displacement_noise_rms(), q / std::sqrt(12.0));
  out.force_noise = loop.force_noise_rms();
}

void declare_stage(const config::DelayStage& stage, DeclaredActuator& out) {
  const auto add = [&](Effect e, const std::string& param, double value, const std::string& text) {
    for (Effect have : out.effects) {
      if (have == e) return;  // one of each kind: the first stage's value seeds the fit
    }
    out.effects.push_back(e);
    out.parameters.push_back({param, value, std::nullopt, std::nullopt, false});
    out.names.push_back(text);
  };
  ++out.stages;
  if (stage.amplitude_gain() != 0.0) out.gain *= stage.amplitude_gain();
  if (stage.has_tracking_loop()) declare_noise(stage.tracking_loop(), out);
  if (stage.has_shift()) {
    if (!out.delay) out.delay = stage.shift().delay();
    add(Effect::kDelay, "delay", stage.shift().delay(),
        "shift " + std::to_string(stage.shift().delay()) + " s");
  } else if (stage.has_first_order()) {
    const double t = stage.first_order().time_constant();
    add(Effect::kFirstOrder, "time_constant", t, "first_order " + std::to_string(t) + " s");
  } else if (stage.has_transfer_function() && stage.transfer_function().denominator_size() == 3) {
    const double wn = std::sqrt(stage.transfer_function().denominator(2));
    add(Effect::kSecondOrder, "natural_frequency", wn,
        "second_order " + std::to_string(wn) + " rad/s");
  } else if (stage.has_backlash()) {
    const double w = stage.backlash().width();
    add(Effect::kBacklash, "width", w, "backlash " + std::to_string(w) + " m");
  } else if (stage.has_velocity_limit()) {
    const double v = stage.velocity_limit().max_velocity();
    add(Effect::kVelocitySaturation, "max_velocity", v,
        "velocity_limit " + std::to_string(v) + " m/s");
  } else if (stage.has_stroke_limit()) {
    const double s = stage.stroke_limit().stroke();
    add(Effect::kStrokeLimit, "stroke", s, "stroke_limit " + std::to_string(s) + " m");
  }
}

DeclaredActuator declared_actuator(const config::Study& study, const std::string& case_name) {
  DeclaredActuator out;
  if (const config::Case* c = run_case(study, case_name)) {
    for (const auto& stage : c->delay()) declare_stage(stage, out);
  }
  for (const auto& node : study.deployment().nodes()) {
    if (node.kind() != config::NodeSpec::ACTUATOR_EMULATOR) continue;
    for (const auto& stage : node.receive_delay()) declare_stage(stage, out);
  }
  if (out.effects.empty()) out.effects.push_back(Effect::kDelay);
  // Nothing declared between the command and the rig: the free delay's declared value is 0. It
  // stays undeclared to the fit (the library's starting guesses, 0 among them, are all tried) and
  // is only what the fitted one is judged against.
  if (out.stages == 0) out.delay = 0.0;
  out.parameters.push_back({"gain", out.gain, std::nullopt, std::nullopt, false});
  return out;
}

// An added effect is named only when it paid when added and still pays in the final model: the
// final model refitted without it loses held-out error (a step taken on the way, whose work a
// later refit does without, is not an effect of the rig).
bool step_paid(const SelectionStep& step) {
  return step.before.heldout_error - step.after.heldout_error > kMinErrorRemoved &&
         step.own_error_removed > kMinErrorRemoved;
}

// The study's storey model as force-channel effects (actuator_path.h), the force stages the case
// and the emulators declare (viscous_force: damping, friction_force: coulomb_friction,
// inertia_force: inertia, force_delay: delay), and what a declared tracking loop adds to the force
// the integrator receives (core/tracking.h): the benchmark plant's specimen inertia and damping,
// the load cell's delay of force_delay_periods servo periods.
std::vector<Effect> declared_specimen(const config::Study& study, const std::string& case_name) {
  const config::RestoringForce& model = study.substructuring().model();
  std::vector<Effect> out{Effect::kStiffness};
  if (model.has_bouc_wen()) out.push_back(Effect::kBoucWen);
  if (model.has_bilinear()) out.push_back(Effect::kElastoPlastic);
  const auto add = [&](Effect e) {
    if (std::find(out.begin(), out.end(), e) == out.end()) out.push_back(e);
  };
  const auto declare = [&](const config::DelayStage& stage) {
    if (stage.has_viscous_force()) add(Effect::kDamping);
    if (stage.has_friction_force()) add(Effect::kCoulomb);
    if (stage.has_inertia_force()) add(Effect::kInertia);
    if (stage.has_force_delay()) add(Effect::kDelay);
    if (!stage.has_tracking_loop()) return;
    if (stage.tracking_loop().has_benchmark_plant()) {
      add(Effect::kInertia);
      add(Effect::kDamping);
    }
    if (stage.tracking_loop().force_delay_periods() > 0) add(Effect::kDelay);
  };
  if (const config::Case* c = run_case(study, case_name))
    for (const auto& stage : c->delay()) declare(stage);
  for (const auto& node : study.deployment().nodes())
    if (node.kind() == config::NodeSpec::ACTUATOR_EMULATOR)
      for (const auto& stage : node.receive_delay()) declare(stage);
  return out;
}

// The force channel against the declared specimen: the effects its final model holds beyond the
// declared ones (those a step added only when they removed held-out error), and a stiffness off
// the declared one.
void judge_specimen(const Identification& id, ActuatorPath& out) {
  const auto* c = id.find(Channel::kForce);
  if (!c) return;
  const SignalScales scales = signal_scales(identified_signals(id, Channel::kForce));
  // The initial stiffness, as the declared storey model's: a hysteretic fit's own stiffness term
  // is its post-yield part.
  const SpecimenModel fitted = specimen_model(c->final_fit.model, scales);
  out.fitted_stiffness =
      fitted.initial_stiffness > 0.0
          ? fitted.initial_stiffness
          : c->final_fit.model.param(Effect::kStiffness, "stiffness", scales).value_or(0.0);
  for (Effect e : c->final_fit.model.effects) {
    if (std::find(c->declared.begin(), c->declared.end(), e) != c->declared.end()) continue;
    bool paid = true;
    for (const auto& step : c->steps)
      if (step.effect == e) paid = step_paid(step);
    if (paid) out.specimen_undeclared.push_back(effect_name(e));
  }
  if (out.declared_stiffness > 0.0 && std::abs(out.fitted_stiffness - out.declared_stiffness) >
                                          kStiffnessTolerance * out.declared_stiffness)
    out.specimen_undeclared.push_back("stiffness change");
}

// Actuator a's channels, each answer at the step whose command it answers (platform_replay.h
// aligned: `used` is the actuator's row of the platform's schedule, empty when every step used
// its own answer).
MeasuredData actuator_data(const std::filesystem::path& record, const runtime::RunMeasurements& m,
                           std::size_t steps, int a, const std::vector<std::int64_t>& used) {
  MeasuredData data;
  data.source = record.string() + " actuator " + std::to_string(a + 1);
  std::vector<double> realised, force;
  for (std::size_t k = 0; k < steps; ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    data.time.push_back(m.steps.time[k]);
    data.command.push_back(m.steps.command(row, a));
    realised.push_back(m.steps.realised(row, a));
    force.push_back(m.steps.measured_force(row, a));
  }
  data.measured = aligned(used, realised);
  data.force = aligned(used, force);
  validate(data, kDefaultMinSamples);
  return data;
}

ActuatorPath identify_actuator(const MeasuredData& data, const runtime::RunHeader& header, int a,
                               const IdentifyOptions& base) {
  const DeclaredActuator declared = declared_actuator(header.study(), header.case_name());
  IdentifyOptions options = base;
  options.declared_actuator = declared.effects;
  options.actuator_parameters = declared.parameters;
  options.declared_specimen = declared_specimen(header.study(), header.case_name());
  ActuatorPath out;
  for (Effect e : options.declared_specimen) out.declared_specimen.push_back(effect_name(e));
  out.actuator = a + 1;
  out.declared = declared.names;
  out.declared_gain = declared.gain;
  out.declared_displacement_noise = declared.displacement_noise;
  out.declared_force_noise = declared.force_noise;
  out.id = identify(data, options);
  if (const auto* c = out.id.find(Channel::kMeasured)) {
    const SignalScales scales = signal_scales(out.id.signals.front());
    out.fitted_gain = c->final_fit.model.param(std::nullopt, "gain", scales).value_or(1.0);
    for (const auto& step : c->steps) {
      if (step_paid(step)) {
        out.undeclared.push_back(effect_name(step.effect));
      }
    }
    if (std::abs(out.fitted_gain - declared.gain) > kGainTolerance * declared.gain) {
      out.undeclared.push_back("gain error");
    }
    if (declared.delay) {
      out.delay_declared = true;
      out.declared_delay = *declared.delay;
      out.fitted_delay = c->final_fit.model.param(Effect::kDelay, "delay", scales).value_or(0.0);
      if (std::abs(out.fitted_delay - out.declared_delay) >
          std::max(kDelayTolerance * out.declared_delay, 0.25 * header.dt())) {
        out.undeclared.push_back("delay change");
      }
    }
  }
  return out;
}

// Each experimental part's declared initial stiffness (N/m), in actuator order; empty when the
// study cannot be set up here (the comparison is then skipped).
std::vector<double> declared_stiffnesses(const config::Study& study, double dt,
                                         const std::filesystem::path& base_dir) {
  std::vector<double> out;
  try {
    const core::HybridSetup setup = study::base_setup(study, dt, base_dir);
    for (int storey : setup.partition.actuator_storeys)
      out.push_back(
          setup.partition.experimental.at(static_cast<std::size_t>(storey))->initial_stiffness());
  } catch (const std::exception&) {
    out.clear();
  }
  return out;
}

// Which answer each step used, per actuator and numerical storey (platform_replay.h); absent
// when the study's deployment cannot be planned here (the re-run then fails and says why).
std::optional<PlatformReplay> replay_of(const std::filesystem::path& record,
                                        const runtime::RecordContents& contents,
                                        const runtime::RunHeader& header, std::size_t steps) {
  try {
    const config::Study& study = *contents.study_as_run();
    const core::HybridSetup base = study::base_setup(study, header.dt(), record.parent_path());
    return platform_replay(contents.steps(), steps,
                           runtime::answer_sources(study, header.dt(), record.parent_path()),
                           static_cast<int>(base.partition.numerical.size()),
                           static_cast<int>(base.partition.actuator_storeys.size()));
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// The study re-run over the identified steps from the record's ground acceleration.
RunResidual residual(const std::filesystem::path& record, const runtime::RecordContents& contents,
                     const runtime::RunHeader& header, const runtime::RunMeasurements& m,
                     const RunIdentification& run) {
  ResidualInput input;
  input.study = contents.study_as_run();
  input.case_name = header.case_name();
  input.clock = m.clock;
  input.base_dir = record.parent_path();
  input.motion.name = record.stem().string();
  input.motion.dt = header.dt();
  for (const runtime::StepRecord* step : contents.steps()) {
    if (input.motion.acceleration.size() == run.steps) break;
    input.motion.acceleration.push_back(step->ground_acceleration());
  }
  const core::Mat recorded = m.steps.displacement.topRows(static_cast<Eigen::Index>(run.steps));
  input.recorded = &recorded;
  input.recorded_dofs = m.steps.dofs;
  input.actuators = &run.actuators;
  input.platform = run.replay ? &*run.replay : nullptr;
  // The descriptions and each channel's events, each put back in its own re-run.
  std::vector<Unexplained> described = run.unexplained;
  for (auto& u : event_residuals(run.floors)) described.push_back(std::move(u));
  input.unexplained = &described;
  input.hold_moving = run.hold_moving;
  try {
    return run_residual(input);
  } catch (const std::invalid_argument& e) {
    bad(record, "header", std::string("re-run of its study: ") + e.what());
  }
}

// Each description's share of the re-run's remaining error (run_residual.h described).
void set_shares(const RunResidual& residual, std::vector<Unexplained>& unexplained) {
  for (Unexplained& u : unexplained)
    for (const ResidualShare& s : residual.described)
      if (s.link == u.part && s.effect == u.channel_word) u.share = s.share;
}

// The named effect `worse` (a re-run removal, run_residual.h effects) moved from its path's named
// effects to its rejected ones; false when no path names it (nothing to take out).
bool reject(const ResidualShare& worse, std::vector<ActuatorPath>& paths) {
  for (ActuatorPath& path : paths)
    for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
      auto& named = channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared;
      const auto at = std::find(named.begin(), named.end(), worse.effect);
      if (at == named.end() || part_of(worse.effect, channel, path.actuator) != worse.link)
        continue;
      named.erase(at);
      path.rejected.push_back({channel, worse.link, worse.effect, -worse.removed, ""});
      restore_merged_constant(path, named, worse.effect);
      return true;
    }
  return false;
}

// A named effect of one path, on its channel (ActuatorPath::undeclared or specimen_undeclared).
struct NamedEffect {
  std::size_t path = 0;
  Channel channel = Channel::kMeasured;
  std::string effect;
};

std::vector<std::string>& named_on(ActuatorPath& path, Channel channel) {
  return channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared;
}

// Every effect the paths name but noise (random: never re-run), moved from the named lists to the
// rejected ones (so that rig_models takes each out of the fitted models) with the reason `why`.
std::vector<NamedEffect> take_out_named(std::vector<ActuatorPath>& paths, const std::string& why) {
  std::vector<NamedEffect> out;
  for (std::size_t p = 0; p < paths.size(); ++p)
    for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
      std::vector<std::string>& named = named_on(paths[p], channel);
      for (const std::string& effect : named) {
        if (effect == "noise") continue;
        out.push_back({p, channel, effect});
        paths[p].rejected.push_back(
            {channel, part_of(effect, channel, paths[p].actuator), effect, 0.0, why});
      }
      std::erase_if(named, [](const std::string& e) { return e != "noise"; });
    }
  return out;
}

// `n` named again: out of its path's rejected effects, back among the named ones.
void put_back(const NamedEffect& n, std::vector<ActuatorPath>& paths) {
  ActuatorPath& path = paths[n.path];
  std::erase_if(path.rejected, [&](const ActuatorPath::Rejected& r) {
    return r.channel == n.channel && r.effect == n.effect;
  });
  named_on(path, n.channel).push_back(n.effect);
}

// The re-run from the declared model (run_record.h keep_what_helps): each named effect put back
// only where it lowers the whole record's worst-floor NRMSE, then the moving parameters.
void fall_back_to_declared(RunIdentification& run, const std::function<RunResidual()>& rerun) {
  const std::string why = "the re-run with every named effect left " +
                          percent_text(run.residual->identified) + " over the whole record, " +
                          "the declared model " + percent_text(run.residual->declared);
  const std::vector<NamedEffect> named = take_out_named(run.actuators, why);
  run.hold_moving = false;
  run.residual = rerun();
  std::string kept;
  for (const NamedEffect& n : named) {
    put_back(n, run.actuators);
    RunResidual with = rerun();
    ActuatorPath& path = run.actuators[n.path];
    const std::string part = part_of(n.effect, n.channel, path.actuator);
    if (with.identified < run.residual->identified - kMinErrorRemoved) {
      run.residual = std::move(with);
      kept += (kept.empty() ? "" : ", ") + part + ": " + n.effect;
      continue;
    }
    named_on(path, n.channel).pop_back();
    path.rejected.push_back({n.channel, part, n.effect,
                             std::max(0.0, with.identified - run.residual->identified),
                             why +
                                 "; put back on the declared model it does not lower the "
                                 "whole record's NRMSE (" +
                                 percent_text(run.residual->identified) + " -> " +
                                 percent_text(with.identified) + ")"});
  }
  run.hold_moving = true;
  RunResidual moving = rerun();
  if (moving.identified < run.residual->identified - kMinErrorRemoved)
    run.residual = std::move(moving);
  else
    run.hold_moving = false;
  run.residual->notes.push_back(why +
                                ": re-run from the declared model with only what lowers it (" +
                                (kept.empty() ? std::string("no named effect") : kept) +
                                (run.hold_moving ? ", the moving parameters" : "") + ")");
}

}  // namespace

void keep_what_helps(RunIdentification& run, const std::function<RunResidual()>& rerun) {
  while (run.residual) {
    const ResidualShare* worst = nullptr;
    for (const ResidualShare& s : run.residual->effects)
      if (s.removed < -kMinErrorRemoved && (!worst || s.removed < worst->removed)) worst = &s;
    if (!worst || !reject(*worst, run.actuators)) break;
    run.residual = rerun();
  }
  if (run.residual && !run.residual->declared_diverged &&
      run.residual->identified > run.residual->declared + kMinErrorRemoved)
    fall_back_to_declared(run, rerun);
}

bool is_run_record(const std::filesystem::path& path) { return path.extension() == ".rthsrec"; }

RunIdentification identify_run_record(const std::filesystem::path& record,
                                      const IdentifyOptions& options) {
  const runtime::RecordContents contents = read_checked(record);
  const runtime::RunHeader& header = *contents.header();
  const runtime::RunMeasurements m = runtime::measure_run(contents);
  RunIdentification out;
  out.record = record.string();
  out.clock = m.clock;
  out.case_name = m.case_name;
  out.study = *contents.study_as_run();
  out.steps = usable_steps(m.steps);
  out.held = held_note(contents, m, out.steps);
  out.inputs = study::inputs_source(out.study, record.parent_path());
  if (out.steps < kDefaultMinSamples) {
    bad(record, "steps",
        std::to_string(out.steps) + " usable steps, at least " +
            std::to_string(kDefaultMinSamples) + " are needed");
  }
  out.duration = m.steps.time[out.steps - 1] - m.steps.time.front();
  out.platform = runtime::diagnose_record_deadlines(contents);
  out.links = identify_links(record, header, m, m.steps.time[out.steps - 1]);
  const std::vector<double> stiffness =
      declared_stiffnesses(out.study, header.dt(), record.parent_path());
  out.replay = replay_of(record, contents, header, out.steps);
  for (int a = 0; a < header.actuators(); ++a) {
    const std::vector<std::int64_t> used =
        out.replay ? actuator_row(out.replay->schedule, a) : std::vector<std::int64_t>{};
    out.actuators.push_back(
        identify_actuator(actuator_data(record, m, out.steps, a, used), header, a, options));
    ActuatorPath& path = out.actuators.back();
    if (static_cast<std::size_t>(a) < stiffness.size())
      path.declared_stiffness = stiffness[static_cast<std::size_t>(a)];
    judge_specimen(path.id, path);
    judge_sensors(path);
    estimate_effects(path);
    judge_named(path);
    judge_plausible(path);
    merge_constant_changes(path);
    std::vector<Unexplained> described = describe_with_noise_periods(path);
    judge_noise_beside(path, described);
    for (auto& f : channel_floors(path)) out.floors.push_back(std::move(f));
    for (auto& u : described) out.unexplained.push_back(std::move(u));
  }
  const auto& channels = options.channels;
  if (std::find(channels.begin(), channels.end(), Channel::kMeasured) != channels.end()) {
    if (options.progress) options.progress({0, 0, "re-run: declared and identified models"});
    out.residual = residual(record, contents, header, m, out);
    keep_what_helps(out, [&] { return residual(record, contents, header, m, out); });
    set_shares(*out.residual, out.unexplained);
    set_event_shares(out.residual->described, out.floors);
  }
  out.findings = collect_findings(out.links, out.actuators, out.residual ? &*out.residual : nullptr,
                                  out.clock);
  describe_direction_delays(out.actuators, out.unexplained, out.findings,
                            out.residual ? &*out.residual : nullptr);
  return out;
}

}  // namespace rths::identify
