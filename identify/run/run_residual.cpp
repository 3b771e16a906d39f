#include "identify/run/run_residual.h"

#include <algorithm>
#include <functional>
#include <memory>
#include <random>
#include <span>
#include <sstream>
#include <stdexcept>

#include "core/metrics.h"
#include "identify/fit/effect_parameters.h"
#include "identify/model/study_config.h"
#include "identify/run/actuator_path.h"
#include "identify/run/sensors.h"
#include "identify/run/unexplained.h"
#include "study/restoring_force_config.h"
#include "study/study.h"

namespace rths::identify {
namespace {

// The record's case; a record whose study lost that case's name is read with its first case.
const config::Case& run_case(const config::Study& study, const std::string& name) {
  if (const config::Case* c = study::case_named(study, name)) return *c;
  if (study.cases().empty()) throw std::invalid_argument("study: no cases");
  return study.cases(0);
}

// What one actuator's re-run uses in place of the declared: its actuator path's model
// (channel measured), its specimen's (channel force: the storey model and the load cell) and its
// displacement sensor's scale (sensors.h rig_models); nullptr keeps the declared.
struct RigModel {
  const ChannelModel* actuator = nullptr;
  const ChannelModel* specimen = nullptr;
  double displacement_scale = 1.0;
  const std::vector<Effect>* held = nullptr;  // RigModels::held_by_declared
  std::vector<MovingParameter> moving;        // held moving (run_residual.h)
};

// `model` without its moving parameter `effect`.
RigModel without_moving(RigModel model, const std::string& effect) {
  std::erase_if(model.moving, [&](const MovingParameter& m) { return m.effect == effect; });
  return model;
}

// The record's time base of a channel's fitted drifts (study_config.h RigRecord).
RigRecord rig_record(const ChannelSignals& signals, const SignalScales& scales) {
  return {signals.time.empty() ? 0.0 : signals.time.front(), scales.duration};
}

// Actuator a's model as study stages with the rig's own effects, behind the declared case's
// compensation.
config::Case model_case(const ChannelModel& model, const SignalScales& scales, const RigRecord& rig,
                        const config::Case& declared, std::vector<std::string>* left_out) {
  const ActuatorCase identified = actuator_case(model, scales, declared.name(), rig);
  if (left_out) *left_out = identified.left_out;
  config::Case out = declared;
  out.clear_delay();
  for (const auto& stage : identified.study_case.delay()) *out.add_delay() = stage;
  return out;
}

// A channel's described residual put back where the channel reads it (run_residual.h described):
// added to the force the integrator receives (force channel) or to the motion (measured channel),
// linear in time between the record's samples, 0 outside them.
class DescribedResidual final : public core::DelayStage {
 public:
  explicit DescribedResidual(const Unexplained& u)
      : time_(&u.time), values_(&u.description.described), force_(u.channel == Channel::kForce) {}
  void reset() override { now_ = 0.0; }
  std::unique_ptr<core::DelayStage> clone() const override {
    return std::make_unique<DescribedResidual>(*this);
  }
  std::string describe() const override { return "described residual"; }
  double nominal_delay() const override { return 0.0; }
  double measure_force(double force) override { return force_ ? force + at(now_) : force; }

 protected:
  double step_unscaled(const core::CommandSample& in) override {
    now_ = in.time;
    return force_ ? in.displacement : in.displacement + at(in.time);
  }

 private:
  double at(double t) const {
    const std::vector<double>& time = *time_;
    const std::vector<double>& values = *values_;
    if (time.size() < 2 || t < time.front() || t > time.back()) return 0.0;
    const auto i =
        static_cast<std::size_t>(std::upper_bound(time.begin(), time.end(), t) - time.begin());
    if (i >= time.size()) return values.back();
    const double s = (t - time[i - 1]) / (time[i] - time[i - 1]);
    return values[i - 1] + s * (values[i] - values[i - 1]);
  }
  const std::vector<double>* time_;
  const std::vector<double>* values_;
  bool force_ = false;
  double now_ = 0.0;
};

struct Rerun {
  core::SimulationResult result;
  std::vector<double> floors;  // NRMSE per DOF
  double worst = 0.0;
};

// The DOF (0-based) the record's column `i` holds (ResidualInput::recorded_dofs).
int dof_of(const std::vector<int>& recorded_dofs, Eigen::Index i) {
  return recorded_dofs.empty() ? static_cast<int>(i)
                               : recorded_dofs.at(static_cast<std::size_t>(i));
}

// The column of `result` that holds the DOF of the record's column `i`; throws
// std::invalid_argument when the re-run has no such DOF.
Eigen::Index rerun_column(const core::SimulationResult& result,
                          const std::vector<int>& recorded_dofs, Eigen::Index i) {
  const int dof = dof_of(recorded_dofs, i);
  const Eigen::Index column = result.column_of_dof(dof);
  if (column < 0)
    throw std::invalid_argument("the record holds DOF " + std::to_string(dof + 1) +
                                ", the study's model has no such DOF");
  return column;
}

// Each recorded column against the re-run's column of the same DOF.
Rerun compare(core::SimulationResult result, const core::Mat& recorded,
              const std::vector<int>& recorded_dofs) {
  Rerun out;
  const auto n = std::min<Eigen::Index>(static_cast<Eigen::Index>(result.steps()), recorded.rows());
  for (Eigen::Index i = 0; i < recorded.cols(); ++i) {
    const Eigen::VectorXd rec = recorded.col(i).head(n),
                          sim = result.displacement.col(rerun_column(result, recorded_dofs, i))
                                    .head(n);
    const double e = core::nrmse(std::span<const double>(rec.data(), static_cast<std::size_t>(n)),
                                 std::span<const double>(sim.data(), static_cast<std::size_t>(n)));
    out.floors.push_back(e);
    out.worst = std::max(out.worst, e);
  }
  out.result = std::move(result);
  return out;
}

// What the re-run cannot hold of an identified specimen: specimen_model's left-out notes
// ("effect: why") that no force stage holds (study_config.h add_force_stages), e.g. a cubic
// stiffness.
std::vector<std::string> not_held(const ChannelModel& specimen, const SignalScales& scales) {
  std::vector<std::string> out;
  for (const auto& note : specimen_model(specimen, scales).left_out) {
    bool held = false;
    try {
      held = held_by_force_stages(parse_effect(note.substr(0, note.find(':'))));
    } catch (const std::invalid_argument&) {}
    if (!held) out.push_back(note);
  }
  return out;
}

// Whether `notes` (not_held) name `effect`.
bool names(const std::vector<std::string>& notes, const std::string& effect) {
  for (const auto& n : notes)
    if (n.rfind(effect + ":", 0) == 0) return true;
  return false;
}

// Shares of each removal in the sum of the positive ones.
void set_shares(std::vector<ResidualShare>& shares) {
  double sum = 0.0;
  for (const auto& s : shares) sum += std::max(0.0, s.removed);
  for (auto& s : shares) s.share = sum > 0.0 ? std::max(0.0, s.removed) / sum : 0.0;
}

// The declared setup and re-runs of it with some actuators' models in place.
class Reruns {
 public:
  explicit Reruns(const ResidualInput& input)
      : input_(input),
        declared_(declared_case(*input.study, run_case(*input.study, input.case_name))) {
    prepared_.config = *input.study;
    prepared_.base_dir = input.base_dir;
    prepared_.motion = input.motion;
    prepared_.base = study::base_setup(*input.study, input.motion.dt, input.base_dir);
    setup_ = study::setup_for_case(prepared_, declared_);
    if (setup_.delays.size() != input.actuators->size()) {
      throw std::invalid_argument("study: " + std::to_string(setup_.delays.size()) +
                                  " actuators, the record has " +
                                  std::to_string(input.actuators->size()));
    }
  }
  // The rig models in `models` in place of the declared ones, actuator by actuator; `replayed`:
  // on the answers the run's loop used (the platform's schedule), where it has one.
  // `described`: a channel's described residual put back (DescribedResidual), or none.
  Rerun run(const std::vector<RigModel>& models, bool replayed = false,
            const Unexplained* described = nullptr) const {
    return run(
        models, replayed,
        described ? std::span<const Unexplained>(described, 1) : std::span<const Unexplained>());
  }
  // As above, with every residual of `put_back` put back.
  Rerun run(const std::vector<RigModel>& models, bool replayed,
            std::span<const Unexplained> put_back) const {
    core::HybridSetup setup = setup_;
    for (std::size_t a = 0; a < models.size(); ++a) {
      const RigModel& m = models[a];
      if (!m.actuator && !m.specimen && m.moving.empty()) continue;
      config::Case c = m.actuator ? model_case(*m.actuator, scales(a), rig(a, Channel::kMeasured),
                                               declared_, nullptr)
                                  : declared_;
      if (m.specimen) {
        add_force_stages(*m.specimen, scales(a, Channel::kForce), rig(a, Channel::kForce), c,
                         m.actuator || !m.held ? std::vector<Effect>{} : *m.held);
        place_specimen(*m.specimen, a, setup);
      } else if (m.actuator) {
        keep_declared_force_stages(declared_, c);
      }
      add_displacement_scale(m.displacement_scale, c);
      for (const MovingParameter& moving : m.moving) hold_moving_delay(moving, c);
      setup.delays[a] = study::setup_for_case(prepared_, c).delays[a];
      for (const MovingParameter& moving : m.moving)
        if (auto stage = moving_stage(moving, m.displacement_scale))
          setup.delays[a].add(std::move(stage));
    }
    for (const Unexplained& described : put_back) {
      const auto a = static_cast<std::size_t>(described.actuator - 1);
      if (a < setup.delays.size())
        setup.delays[a].add(std::make_unique<DescribedResidual>(described));
    }
    const core::AnswerSchedule& answers =
        replayed && replays() ? input_.platform->schedule : no_replay_;
    core::SimulationOptions options;
    options.kept_dofs = input_.recorded_dofs;
    return compare(core::simulate(setup, prepared_.motion, options, answers), *input_.recorded,
                   input_.recorded_dofs);
  }
  bool replays() const { return input_.platform && input_.platform->late_steps > 0; }
  // The worst floor's NRMSE of `rerun` over `steps` (0-based) alone.
  double worst_over(const Rerun& rerun, const std::vector<std::size_t>& steps) const {
    const core::Mat& recorded = *input_.recorded;
    const auto n =
        std::min<Eigen::Index>(static_cast<Eigen::Index>(rerun.result.steps()), recorded.rows());
    double worst = 0.0;
    for (Eigen::Index i = 0; i < recorded.cols(); ++i) {
      const Eigen::Index column = rerun_column(rerun.result, input_.recorded_dofs, i);
      std::vector<double> rec, sim;
      for (std::size_t j : steps) {
        if (static_cast<Eigen::Index>(j) >= n) break;
        rec.push_back(recorded(static_cast<Eigen::Index>(j), i));
        sim.push_back(rerun.result.displacement(static_cast<Eigen::Index>(j), column));
      }
      worst = std::max(worst, core::nrmse(rec, sim));
    }
    return worst;
  }
  SignalScales scales(std::size_t a, Channel channel = Channel::kMeasured) const {
    return signal_scales(identified_signals((*input_.actuators)[a].id, channel));
  }
  RigRecord rig(std::size_t a, Channel channel) const {
    return rig_record(identified_signals((*input_.actuators)[a].id, channel), scales(a, channel));
  }
  const config::Case& declared() const { return declared_; }

 private:
  // The identified storey model of actuator a's specimen in place of the declared one, at its
  // identified initial stiffness (study_config.h specimen_model); the declared one stays when
  // the fit has no displacement-dependent force.
  void place_specimen(const ChannelModel& specimen, std::size_t a, core::HybridSetup& setup) const {
    const SpecimenModel model = specimen_model(specimen, scales(a, Channel::kForce));
    if (!model.restoring_force || !(model.initial_stiffness > 0.0)) return;
    const auto storey = static_cast<std::size_t>(setup.partition.actuator_storeys.at(a));
    setup.partition.experimental.at(storey) =
        study::make_storey_factory(*model.restoring_force)(model.initial_stiffness);
  }

  const ResidualInput& input_;
  const core::AnswerSchedule no_replay_;
  config::Case declared_;
  study::PreparedStudy prepared_;
  core::HybridSetup setup_;
};

// Per actuator link its whole identified rig alone (actuator, sensors, specimen), and per
// undeclared effect the model without it.
void add_shares(const Reruns& reruns, const std::vector<ActuatorPath>& paths,
                const std::vector<RigModel>& all, RunResidual& out) {
  const std::vector<RigModel> none(paths.size());
  for (std::size_t a = 0; a < paths.size(); ++a) {
    const std::string n = std::to_string(a + 1);
    std::vector<RigModel> alone = none;
    alone[a] = all[a];
    out.links.push_back({"actuator " + n, "all", out.declared - reruns.run(alone).worst, 0.0});
    const auto removes = [&](const std::string& part, const std::string& effect,
                             const RigModel& reduced) {
      std::vector<RigModel> models = all;
      models[a] = reduced;
      out.effects.push_back({part, effect, reruns.run(models, true).worst - out.identified, 0.0});
    };
    const int actuator = static_cast<int>(a) + 1;
    for (const MovingParameter& moving : all[a].moving)
      removes(moving.part, moving.effect, without_moving(all[a], moving.effect));
    const auto held_moving = [&](const std::string& effect) {
      return std::any_of(all[a].moving.begin(), all[a].moving.end(),
                         [&](const MovingParameter& m) { return m.effect == effect; });
    };
    for (const auto& effect : paths[a].undeclared) {
      if (effect == "noise" || held_moving(effect)) continue;  // noise: random, not re-run
      const std::string part = part_of(effect, Channel::kMeasured, actuator);
      RigModel reduced_rig = all[a];
      if (effect == "scale") {  // the sensor reading true: the same loop, another reading
        reduced_rig.displacement_scale = 1.0;
        removes(part, effect, reduced_rig);
        continue;
      }
      if (!all[a].actuator) continue;  // the declared actuator stays: nothing to take out
      const ChannelModel reduced =
          without_named(*all[a].actuator, paths[a], effect, reruns.scales(a));
      reduced_rig.actuator = &reduced;
      removes(part, effect, reduced_rig);
    }
    if (!all[a].specimen) continue;
    // An effect the re-run cannot hold has no share: it is named `not re-run` with the reason.
    const std::vector<std::string> left_out =
        not_held(*all[a].specimen, reruns.scales(a, Channel::kForce));
    for (const auto& effect : paths[a].specimen_undeclared) {
      if (effect == "noise" || held_moving(effect) || names(left_out, effect)) continue;
      const ChannelModel reduced =
          without_named(*all[a].specimen, paths[a], effect, reruns.scales(a, Channel::kForce));
      RigModel reduced_rig = all[a];
      reduced_rig.specimen = &reduced;
      removes(part_of(effect, Channel::kForce, actuator), effect, reduced_rig);
    }
  }
  if (reruns.replays())
    out.links.push_back({"platform", "late answers", reruns.run(all).worst - out.identified, 0.0});
  set_shares(out.links);
  set_shares(out.effects);
}

// The moving parameters `path` names, then those its channels' described trends move where no
// named one moves the same parameter (moving_parameter.h).
std::vector<MovingParameter> candidates(const ActuatorPath& path,
                                        const std::vector<Unexplained>* unexplained,
                                        bool specimen_rerun) {
  std::vector<MovingParameter> out = moving_parameters(path);
  for (const Unexplained& u : unexplained ? *unexplained : std::vector<Unexplained>{}) {
    if (u.actuator != path.actuator) continue;
    std::optional<MovingParameter> moving = described_moving(u, path, specimen_rerun);
    if (moving && std::none_of(out.begin(), out.end(), [&](const MovingParameter& m) {
          return m.effect == moving->effect;
        }))
      out.push_back(std::move(*moving));
  }
  return out;
}

// Each moving parameter the paths name (or their descriptions move) tried in the re-run (run_residual.h moving): kept in `all`
// where it lowers the worst floor's held-out NRMSE below its constant's by kMinMovingGain.
void choose_moving(const Reruns& reruns, const std::vector<ActuatorPath>& paths,
                   const std::vector<Unexplained>* unexplained, std::vector<RigModel>& all,
                   RunResidual& out) {
  for (std::size_t a = 0; a < paths.size(); ++a)
    for (MovingParameter& moving : candidates(paths[a], unexplained, all[a].specimen != nullptr)) {
      const std::vector<std::size_t>& heldout = paths[a].id.split.heldout;
      std::vector<RigModel> with = all;
      with[a].moving.push_back(moving);
      MovingRerun tried{moving, reruns.worst_over(reruns.run(all, true), heldout),
                        reruns.worst_over(reruns.run(with, true), heldout), false};
      tried.kept = tried.moving < tried.constant - kMinMovingGain;
      if (tried.kept) all[a] = with[a];
      out.moving.push_back(std::move(tried));
    }
}

// Whether `note` ("effect: why" or "time-varying gain: ...") is about `effect`, whichever of
// '_', '-' and ' ' it spells the words with.
bool about(const std::string& note, const std::string& effect) {
  if (note.size() < effect.size()) return false;
  for (std::size_t i = 0; i < effect.size(); ++i) {
    const auto word = [](char c) { return c == '-' || c == '_' ? ' ' : c; };
    if (word(note[i]) != word(effect[i])) return false;
  }
  return true;
}

// `notes` without those about a parameter `rig` holds moving.
std::vector<std::string> unless_moving(std::vector<std::string> notes, const RigModel& rig) {
  std::erase_if(notes, [&](const std::string& note) {
    return std::any_of(rig.moving.begin(), rig.moving.end(),
                       [&](const MovingParameter& m) { return about(note, m.effect); });
  });
  return notes;
}

// Per described channel: what putting its described residual back removes from the identified
// re-run's error, and its share of that error.
void add_described(const Reruns& reruns, const std::vector<RigModel>& all,
                   const std::vector<Unexplained>& unexplained, RunResidual& out) {
  for (const Unexplained& u : unexplained) {
    const double removed = out.identified - reruns.run(all, true, &u).worst;
    const double share = out.identified > 0.0 ? std::max(0.0, removed) / out.identified : 0.0;
    out.described.push_back({u.part, u.channel_word, removed, std::min(1.0, share)});
  }
}

// The re-run floor (run_residual.h noise_floor): the identified re-run with each load cell's
// white noise put back as one seeded draw, against the identified re-run, the worst floor's
// RMS difference over the median |u| of the record's column.
double noise_floor(const Reruns& reruns, const std::vector<RigModel>& all,
                   const std::vector<ActuatorPath>& paths, const Rerun& after,
                   const ResidualInput& input) {
  std::mt19937_64 rng(kNoiseFloorSeed);
  std::normal_distribution<double> draw(0.0, 1.0);
  std::vector<Unexplained> noise;
  for (const ActuatorPath& path : paths) {
    if (!path.id.find(Channel::kForce) || !(path.force_noise > 0.0)) continue;
    Unexplained u;
    u.actuator = path.actuator;
    u.channel = Channel::kForce;
    u.time = identified_signals(path.id, Channel::kForce).time;
    for (std::size_t j = 0; j < u.time.size(); ++j)
      u.description.described.push_back(path.force_noise * draw(rng));
    noise.push_back(std::move(u));
  }
  if (noise.empty()) return 0.0;
  const Rerun noisy = reruns.run(all, true, noise);
  const core::Mat& recorded = *input.recorded;
  const Eigen::Index n =
      std::min<Eigen::Index>({static_cast<Eigen::Index>(noisy.result.steps()),
                              static_cast<Eigen::Index>(after.result.steps()), recorded.rows()});
  double worst = 0.0;
  for (Eigen::Index i = 0; i < recorded.cols(); ++i) {
    const Eigen::Index a = rerun_column(after.result, input.recorded_dofs, i),
                       b = rerun_column(noisy.result, input.recorded_dofs, i);
    std::vector<double> rec(static_cast<std::size_t>(n)), moved(rec.size());
    for (Eigen::Index j = 0; j < n; ++j) {
      rec[static_cast<std::size_t>(j)] = recorded(j, i);
      moved[static_cast<std::size_t>(j)] =
          recorded(j, i) + noisy.result.displacement(j, b) - after.result.displacement(j, a);
    }
    worst = std::max(worst, core::nrmse(rec, moved));
  }
  return worst;
}

}  // namespace

config::Case declared_case(const config::Study& study, const config::Case& study_case) {
  config::Case out = study_case;
  out.clear_delay();
  for (const auto& node : study.deployment().nodes()) {
    if (node.kind() != config::NodeSpec::ACTUATOR_EMULATOR) continue;
    for (const auto& stage : node.receive_delay()) *out.add_delay() = stage;
  }
  for (const auto& stage : study_case.delay()) *out.add_delay() = stage;
  return out;
}

RunResidual run_residual(const ResidualInput& input) {
  const auto& paths = *input.actuators;
  const Reruns reruns(input);
  RunResidual out;
  std::vector<RigModels> rigs;
  for (const auto& path : paths) rigs.push_back(rig_models(path));
  std::vector<RigModel> all(paths.size());
  for (std::size_t a = 0; a < paths.size(); ++a) {
    if (rigs[a].actuator) all[a].actuator = &*rigs[a].actuator;
    // The declared specimen stays unless the force channel found it wrong: a re-run changes
    // only what the record contradicts.
    if (rigs[a].specimen) all[a].specimen = &*rigs[a].specimen;
    all[a].displacement_scale = rigs[a].displacement_scale;
    all[a].held = &rigs[a].held_by_declared;
  }
  if (input.hold_moving) choose_moving(reruns, paths, input.unexplained, all, out);
  for (std::size_t a = 0; a < paths.size(); ++a) {
    std::vector<std::string> left_out;
    if (all[a].actuator)
      model_case(*all[a].actuator, reruns.scales(a), reruns.rig(a, Channel::kMeasured),
                 reruns.declared(), &left_out);
    for (const auto& l : unless_moving(left_out, all[a]))
      out.notes.push_back("actuator " + std::to_string(a + 1) + ": " + l);
    if (all[a].specimen)
      for (const auto& l :
           unless_moving(not_held(*all[a].specimen, reruns.scales(a, Channel::kForce)), all[a]))
        out.notes.push_back("specimen " + std::to_string(a + 1) + ": " + l);
  }
  const Rerun before = reruns.run(std::vector<RigModel>(paths.size()));
  const Rerun after = reruns.run(all, true);
  out.steps = std::min<std::size_t>({before.result.steps(), after.result.steps(),
                                     static_cast<std::size_t>(input.recorded->rows())});
  out.declared = before.worst;
  out.identified = after.worst;
  out.declared_diverged = before.result.diverged;
  out.identified_diverged = after.result.diverged;
  for (std::size_t i = 0; i < before.floors.size(); ++i) {
    const int dof = dof_of(input.recorded_dofs, static_cast<Eigen::Index>(i));
    out.floors.push_back({dof + 1, before.floors[i], after.floors[i]});
  }
  const auto rows = static_cast<Eigen::Index>(out.steps);
  out.time.assign(after.result.time.begin(), after.result.time.begin() + rows);
  out.recorded_response = input.recorded->topRows(rows);
  out.declared_response = before.result.displacement.topRows(rows);
  out.identified_response = after.result.displacement.topRows(rows);
  add_shares(reruns, paths, all, out);
  if (input.unexplained) add_described(reruns, all, *input.unexplained, out);
  out.noise_floor = noise_floor(reruns, all, paths, after, input);
  if (reruns.replays()) out.platform = input.platform->text();
  if (input.clock == "real_time")
    out.notes.push_back(reruns.replays()
                            ? "network paths and overruns: in the re-run as the answers the "
                              "loop used, replayed as recorded (" +
                                  out.platform + ")"
                            : "network paths and overruns: every step used its own answers, "
                              "so their lag did not reach the response");
  return out;
}

std::string percent_text(double ratio) {
  std::ostringstream out;
  out.precision(3);
  out << 100.0 * ratio << " %";
  return out.str();
}

}  // namespace rths::identify
