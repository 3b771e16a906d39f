#include "identify/run/run_record.h"

#include "identify/fit/effect_parameters.h"
#include "identify/model/study_config.h"
#include "identify/run/findings.h"
#include "identify/run/sensors.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "runtime/node/plan.h"
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
  const config::Case* named = core::case_named(study, name);
  return named ? named : &study.cases(0);
}

// The declared actuator (run_record.h): the case's stages, then the emulators' own receive
// stages, as effects with the config's values as initial values.
struct DeclaredActuator {
  std::vector<Effect> effects;
  std::vector<ParamDeclaration> parameters;
  std::vector<std::string> names;
  double gain = 1.0;
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
  if (stage.amplitude_gain() != 0.0) out.gain *= stage.amplitude_gain();
  if (stage.has_tracking_loop()) declare_noise(stage.tracking_loop(), out);
  if (stage.has_shift()) {
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

// The study's storey model as force-channel effects (actuator_path.h), and what a declared
// tracking loop adds to the force the integrator receives (core/tracking.h): the benchmark plant's
// specimen inertia and damping, the load cell's delay of force_delay_periods servo periods.
std::vector<Effect> declared_specimen(const config::Study& study, const std::string& case_name) {
  const config::RestoringForce& model = study.substructuring().model();
  std::vector<Effect> out{Effect::kStiffness};
  if (model.has_bouc_wen()) out.push_back(Effect::kBoucWen);
  if (model.has_bilinear()) out.push_back(Effect::kElastoPlastic);
  const auto add = [&](Effect e) {
    if (std::find(out.begin(), out.end(), e) == out.end()) out.push_back(e);
  };
  const auto declare = [&](const config::DelayStage& stage) {
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
    for (const auto& p : declared.parameters) {
      if (p.name != "delay" || !p.initial) continue;
      out.declared_delay = *p.initial;
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
    const core::HybridSetup setup = core::base_setup(study, dt, base_dir);
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
    const core::HybridSetup base = core::base_setup(study, header.dt(), record.parent_path());
    const runtime::DeploymentPlan plan = runtime::make_plan(base, study.deployment());
    return platform_replay(contents.steps(), steps, plan,
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
  input.actuators = &run.actuators;
  input.platform = run.replay ? &*run.replay : nullptr;
  try {
    return run_residual(input);
  } catch (const std::invalid_argument& e) {
    bad(record, "header", std::string("re-run of its study: ") + e.what());
  }
}

}  // namespace

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
  out.inputs = core::inputs_source(out.study, record.parent_path());
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
  }
  const auto& channels = options.channels;
  if (std::find(channels.begin(), channels.end(), Channel::kMeasured) != channels.end()) {
    if (options.progress) options.progress({0, 0, "re-run: declared and identified models"});
    out.residual = residual(record, contents, header, m, out);
  }
  return out;
}

}  // namespace rths::identify

namespace rths::identify {
namespace {

void link_text(const NetworkPath& l, std::ostream& out) {
  out << "link to node " << l.node_id << ": " << l.answers << " answers; round trip beyond the"
      << " injected lag: bias " << l.bias * 1e3 << " ms, jitter " << l.jitter * 1e3
      << " ms, drift over the run " << l.drift_range * 1e3 << " ms; " << l.spikes
      << " spikes; lost " << l.lost << " (longest burst " << l.longest_burst << "), superseded "
      << l.superseded << ", late " << l.late << "; injected " << l.injected_mean * 1e3
      << " ms (declared " << l.declared.round_trip * 1e3 << " ms)\n";
  if (l.effects.empty()) out << "  undeclared effects: none\n";
  for (const auto& e : l.effects) {
    out << "  undeclared: " << e.name << ": " << e.detail;
    if (e.heldout_before > 0.0) {
      out << " (held-out RMS " << e.heldout_before * 1e3 << " -> " << e.heldout_after * 1e3
          << " ms, share " << percent_text(e.share) << ")";
    }
    out << "\n";
  }
}

// The sensors' noise (RMS, as estimated and as declared) and the displacement sensor's scale.
void sensors_text(const ActuatorPath& a, std::ostream& out) {
  const auto precision = out.precision(3);
  out << "  sensors: displacement noise " << a.displacement_noise * 1e3 << " mm RMS (declared "
      << a.declared_displacement_noise * 1e3 << " mm), load cell noise " << a.force_noise
      << " N RMS (declared " << a.declared_force_noise << " N)";
  if (a.displacement_scale != 1.0)
    out << ", displacement sensor scale " << a.displacement_scale << " +/- "
        << a.displacement_scale_error;
  out << "\n";
  out.precision(precision);
}

void actuator_text(const ActuatorPath& a, std::ostream& out) {
  out << "actuator " << a.actuator << ": declared";
  for (const auto& d : a.declared) out << " " << d << ",";
  out << " gain " << a.declared_gain << " (fitted " << a.fitted_gain << ")";
  if (a.declared_delay > 0.0) {
    out << ", delay " << a.declared_delay * 1e3 << " ms (fitted " << a.fitted_delay * 1e3 << " ms)";
  }
  out << "\n";
  for (const auto& c : a.id.channels) {
    out << "  " << channel_name(c.channel) << ": held-out "
        << percent_text(c.declared_fit.heldout_error) << " declared -> "
        << percent_text(c.final_fit.heldout_error) << " identified";
    for (const auto& step : c.steps) {
      out << "; + " << effect_name(step.effect) << " (share " << percent_text(step.own_share)
          << ")";
    }
    out << "\n";
    const SignalScales scales = signal_scales(identified_signals(a.id, c.channel));
    for (const auto& step : c.steps)
      for (const ParameterEstimate& p : effect_parameters(c.final_fit, step.effect, scales))
        out << "    " << effect_name(step.effect) << ": " << p.describe() << "\n";
  }
  out << "  undeclared effects: ";
  for (std::size_t i = 0; i < a.undeclared.size(); ++i) out << (i ? ", " : "") << a.undeclared[i];
  out << (a.undeclared.empty() ? "none\n" : "\n");
  sensors_text(a, out);
  if (a.declared_specimen.empty()) return;
  out << "  specimen: declared";
  for (const auto& d : a.declared_specimen) out << " " << d;
  if (a.declared_stiffness > 0.0) out << ", stiffness " << a.declared_stiffness << " N/m";
  out << " (fitted " << a.fitted_stiffness << " N/m); undeclared: ";
  for (std::size_t i = 0; i < a.specimen_undeclared.size(); ++i)
    out << (i ? ", " : "") << a.specimen_undeclared[i];
  out << (a.specimen_undeclared.empty() ? "none\n" : "\n");
}

void residual_text(const RunResidual& r, std::ostream& out) {
  out << "response re-run in process over " << r.steps << " steps, NRMSE against the record "
      << "(declared -> identified):";
  for (const auto& f : r.floors) {
    out << " floor " << f.dof << " " << percent_text(f.declared) << " -> "
        << percent_text(f.identified) << ";";
  }
  out << (r.declared_diverged ? " the declared model diverges;" : "")
      << (r.identified_diverged ? " the identified model diverges;" : "") << "\n";
  for (const auto* kind : {&r.links, &r.effects}) {
    for (const auto& s : *kind) {
      out << "  " << s.link << (s.effect == "all" ? "" : ": " + s.effect) << " removes "
          << percent_text(s.removed) << " of NRMSE from the worst floor (share "
          << percent_text(s.share) << ")\n";
    }
  }
  for (const auto& n : r.notes) out << "  note: " << n << "\n";
}

nlohmann::json residual_json(const RunResidual& r) {
  nlohmann::json floors = nlohmann::json::array(), links = nlohmann::json::array(),
                 effects = nlohmann::json::array();
  for (const auto& f : r.floors) {
    floors.push_back(
        {{"dof", f.dof}, {"declared_nrmse", f.declared}, {"identified_nrmse", f.identified}});
  }
  for (const auto& [kind, list] : {std::pair{&r.links, &links}, std::pair{&r.effects, &effects}}) {
    for (const auto& s : *kind) {
      list->push_back({{"link", s.link},
                       {"effect", s.effect},
                       {"nrmse_removed", s.removed},
                       {"share", s.share}});
    }
  }
  return {{"steps", r.steps},
          {"floors", floors},
          {"declared_nrmse", r.declared},
          {"identified_nrmse", r.identified},
          {"declared_diverged", r.declared_diverged},
          {"identified_diverged", r.identified_diverged},
          {"links", links},
          {"effects", effects},
          {"notes", r.notes}};
}

nlohmann::json links_json(const RunIdentification& run) {
  nlohmann::json links = nlohmann::json::array();
  for (const auto& l : run.links) {
    nlohmann::json effects = nlohmann::json::array();
    for (const auto& e : l.effects) {
      effects.push_back({{"name", e.name},
                         {"detail", e.detail},
                         {"heldout_rms_before_s", e.heldout_before},
                         {"heldout_rms_after_s", e.heldout_after},
                         {"share", e.share}});
    }
    links.push_back(
        {{"node_id", l.node_id},
         {"answers", l.answers},
         {"bias_s", l.bias},
         {"jitter_s", l.jitter},
         {"drift_range_s", l.drift_range},
         {"spikes", l.spikes},
         {"spike_period_s", l.spike_period},
         {"lost", l.lost},
         {"longest_burst", l.longest_burst},
         {"superseded", l.superseded},
         {"late", l.late},
         {"injected_mean_s", l.injected_mean},
         {"declared_round_trip_s", l.declared.round_trip},
         {"clock_offset_s", l.clock ? nlohmann::json(l.clock->offset) : nlohmann::json()},
         {"heldout_rms_declared_s", l.heldout_declared},
         {"undeclared", effects}});
  }
  return links;
}

nlohmann::json actuators_json(const RunIdentification& run) {
  nlohmann::json actuators = nlohmann::json::array();
  for (const auto& a : run.actuators) {
    nlohmann::json channels = nlohmann::json::array();
    for (const auto& c : a.id.channels) {
      const SignalScales scales = signal_scales(identified_signals(a.id, c.channel));
      nlohmann::json effects = nlohmann::json::array();
      for (const auto& step : c.steps) {
        const nlohmann::json parameters =
            parameters_json(effect_parameters(c.final_fit, step.effect, scales));
        effects.push_back({{"effect", effect_name(step.effect)},
                           {"share", step.own_share},
                           {"parameters", parameters}});
      }
      channels.push_back({{"channel", channel_name(c.channel)},
                          {"declared_heldout_error", c.declared_fit.heldout_error},
                          {"identified_heldout_error", c.final_fit.heldout_error},
                          {"effects", effects}});
    }
    actuators.push_back({{"actuator", a.actuator},
                         {"declared", a.declared},
                         {"declared_gain", a.declared_gain},
                         {"fitted_gain", a.fitted_gain},
                         {"declared_delay_s", a.declared_delay},
                         {"fitted_delay_s", a.fitted_delay},
                         {"channels", channels},
                         {"undeclared", a.undeclared},
                         {"declared_specimen", a.declared_specimen},
                         {"declared_stiffness_n_per_m", a.declared_stiffness},
                         {"fitted_stiffness_n_per_m", a.fitted_stiffness},
                         {"specimen_undeclared", a.specimen_undeclared},
                         {"sensors",
                          {{"displacement_noise_m", a.displacement_noise},
                           {"declared_displacement_noise_m", a.declared_displacement_noise},
                           {"force_noise_n", a.force_noise},
                           {"declared_force_noise_n", a.declared_force_noise},
                           {"displacement_scale", a.displacement_scale},
                           {"displacement_scale_std_error", a.displacement_scale_error}}}});
  }
  return actuators;
}

}  // namespace

std::string run_record_text(const RunIdentification& run) {
  std::ostringstream out;
  out << "record " << run.record << ": case '" << run.case_name << "', " << run.clock << ", "
      << run.held << "; " << run.steps << " steps (" << run.duration << " s) identified\n";
  out << "inputs: " << run.inputs << "\n";
  if (run.platform && run.platform->overruns > 0)
    out << "platform: " << run.platform->overruns << " of " << run.platform->steps
        << " steps overran their deadline (" << run.platform->cause
        << "); the record: " << run.platform->usability << "\n";
  if (run.platform && run.platform->verdict)
    out << "real-time verdict: " << *run.platform->verdict << "\n";
  if (run.replay && run.replay->late_steps > 0)
    out << "answers the loop used: " << run.replay->text()
        << "; the rig is identified on each answer at its own step, the re-run replays them\n";
  for (const auto& l : run.links) link_text(l, out);
  for (const auto& a : run.actuators) actuator_text(a, out);
  if (run.residual) residual_text(*run.residual, out);
  const RunResidual* residual = run.residual ? &*run.residual : nullptr;
  out << findings_text(collect_findings(run.links, run.actuators, residual, run.clock), residual);
  return out.str();
}

nlohmann::json run_record_json(const RunIdentification& run) {
  const nlohmann::json links = links_json(run), actuators = actuators_json(run);
  nlohmann::json out = {
      {"record", run.record},       {"case", run.case_name}, {"clock", run.clock},
      {"held", run.held},           {"inputs", run.inputs},  {"steps", run.steps},
      {"duration_s", run.duration}, {"links", links},        {"actuators", actuators}};
  if (run.residual) out["residual"] = residual_json(*run.residual);
  out["undeclared"] = findings_json(collect_findings(
      run.links, run.actuators, run.residual ? &*run.residual : nullptr, run.clock));
  if (const auto& p = run.platform)
    out["platform"] = {
        {"steps", p->steps},
        {"overruns", p->overruns},
        {"overrun_share", p->overrun_share()},
        {"dominated_by_overruns", p->overrun_share() > runtime::DeadlineDiagnosis::kDominatedShare},
        {"worst_streak", p->worst_streak},
        {"cause", p->cause},
        {"usability", p->usability},
        {"verdict", p->verdict ? nlohmann::json(*p->verdict) : nlohmann::json()}};
  if (const auto& r = run.replay)
    out["answers_used"] = {{"late_steps", r->late_steps},
                           {"mean_age_steps", r->mean_age},
                           {"oldest_steps", r->oldest},
                           {"replayed", r->late_steps > 0}};
  return out;
}

}  // namespace rths::identify
