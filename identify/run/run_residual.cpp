#include "identify/run/run_residual.h"

#include <algorithm>
#include <functional>
#include <span>
#include <stdexcept>

#include "core/metrics.h"
#include "identify/model/study_config.h"
#include "identify/run/actuator_path.h"
#include "study/study.h"

namespace rths::identify {
namespace {

const config::Case& run_case(const config::Study& study, const std::string& name) {
  for (const auto& c : study.cases()) {
    if (c.name() == name) return c;
  }
  if (study.cases().empty()) throw std::invalid_argument("study: no cases");
  return study.cases(0);
}

// The case as the distributed run applied it: the emulators' declared receive stages, then the
// case's delay stages (run_residual.h).
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

// Actuator a's model as study stages, behind the declared case's compensation.
config::Case model_case(const ChannelModel& model, const SignalScales& scales,
                        const config::Case& declared, std::vector<std::string>* left_out) {
  const ActuatorCase identified = actuator_case(model, scales, declared.name());
  if (left_out) *left_out = identified.left_out;
  config::Case out = declared;
  out.clear_delay();
  for (const auto& stage : identified.study_case.delay()) *out.add_delay() = stage;
  return out;
}

struct Rerun {
  core::SimulationResult result;
  std::vector<double> floors;  // NRMSE per DOF
  double worst = 0.0;
};

Rerun compare(core::SimulationResult result, const core::Mat& recorded) {
  Rerun out;
  const auto n = std::min<Eigen::Index>(static_cast<Eigen::Index>(result.steps()), recorded.rows());
  for (Eigen::Index i = 0; i < recorded.cols(); ++i) {
    const Eigen::VectorXd rec = recorded.col(i).head(n), sim = result.displacement.col(i).head(n);
    const double e = core::nrmse(std::span<const double>(rec.data(), static_cast<std::size_t>(n)),
                                 std::span<const double>(sim.data(), static_cast<std::size_t>(n)));
    out.floors.push_back(e);
    out.worst = std::max(out.worst, e);
  }
  out.result = std::move(result);
  return out;
}

// Shares of each removal in the sum of the positive ones.
void set_shares(std::vector<ResidualShare>& shares) {
  double sum = 0.0;
  for (const auto& s : shares) sum += std::max(0.0, s.removed);
  for (auto& s : shares) s.share = sum > 0.0 ? std::max(0.0, s.removed) / sum : 0.0;
}

// The identified model of actuator path `path` with one undeclared effect taken back out.
ChannelModel without(const ActuatorPath& path, const std::string& effect,
                     const SignalScales& scales) {
  const ChannelModel& model = path.id.find(Channel::kMeasured)->final_fit.model;
  if (effect == "gain error" || effect == "delay change") {
    ChannelModel out = model;
    const bool gain = effect == "gain error";
    const auto i = gain ? out.index_of(std::nullopt, "gain", scales)
                        : out.index_of(Effect::kDelay, "delay", scales);
    if (i) out.params[*i] = gain ? path.declared_gain : path.declared_delay;
    return out;
  }
  return without_effect(model, parse_effect(effect), scales);
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
    prepared_.base = core::base_setup(*input.study, input.motion.dt, input.base_dir);
    setup_ = core::setup_for_case(prepared_, declared_);
    if (setup_.delays.size() != input.actuators->size()) {
      throw std::invalid_argument("study: " + std::to_string(setup_.delays.size()) +
                                  " actuators, the record has " +
                                  std::to_string(input.actuators->size()));
    }
  }
  // The models of the actuators in `models` (nullptr: declared) in place.
  Rerun run(const std::vector<const ChannelModel*>& models) const {
    core::HybridSetup setup = setup_;
    for (std::size_t a = 0; a < models.size(); ++a) {
      if (!models[a]) continue;
      const config::Case c = model_case(*models[a], scales(a), declared_, nullptr);
      setup.delays[a] = core::setup_for_case(prepared_, c).delays[a];
    }
    return compare(core::simulate(setup, prepared_.motion), *input_.recorded);
  }
  SignalScales scales(std::size_t a) const {
    return signal_scales((*input_.actuators)[a].id.signals.front());
  }
  const config::Case& declared() const { return declared_; }

 private:
  const ResidualInput& input_;
  config::Case declared_;
  core::PreparedStudy prepared_;
  core::HybridSetup setup_;
};

// Per actuator link its whole model alone, and per undeclared effect the model without it.
void add_shares(const Reruns& reruns, const std::vector<ActuatorPath>& paths,
                const std::vector<const ChannelModel*>& all, RunResidual& out) {
  const std::vector<const ChannelModel*> none(paths.size(), nullptr);
  for (std::size_t a = 0; a < paths.size(); ++a) {
    const std::string link = "actuator " + std::to_string(a + 1);
    std::vector<const ChannelModel*> alone = none;
    alone[a] = all[a];
    out.links.push_back({link, "all", out.declared - reruns.run(alone).worst, 0.0});
    for (const auto& effect : paths[a].undeclared) {
      const ChannelModel reduced = without(paths[a], effect, reruns.scales(a));
      std::vector<const ChannelModel*> models = all;
      models[a] = &reduced;
      out.effects.push_back({link, effect, reruns.run(models).worst - out.identified, 0.0});
    }
  }
  set_shares(out.links);
  set_shares(out.effects);
}

}  // namespace

RunResidual run_residual(const ResidualInput& input) {
  const auto& paths = *input.actuators;
  const Reruns reruns(input);
  RunResidual out;
  std::vector<const ChannelModel*> all(paths.size(), nullptr);
  for (std::size_t a = 0; a < paths.size(); ++a) {
    const auto* c = paths[a].id.find(Channel::kMeasured);
    if (!c) {
      throw std::invalid_argument("actuator " + std::to_string(a + 1) +
                                  ": actuator path not identified");
    }
    all[a] = &c->final_fit.model;
    std::vector<std::string> left_out;
    model_case(*all[a], reruns.scales(a), reruns.declared(), &left_out);
    for (const auto& l : left_out)
      out.notes.push_back("actuator " + std::to_string(a + 1) + ": " + l);
  }
  const Rerun before = reruns.run(std::vector<const ChannelModel*>(paths.size(), nullptr));
  const Rerun after = reruns.run(all);
  out.steps = std::min<std::size_t>({before.result.steps(), after.result.steps(),
                                     static_cast<std::size_t>(input.recorded->rows())});
  out.declared = before.worst;
  out.identified = after.worst;
  out.declared_diverged = before.result.diverged;
  out.identified_diverged = after.result.diverged;
  for (std::size_t i = 0; i < before.floors.size(); ++i) {
    out.floors.push_back({static_cast<int>(i + 1), before.floors[i], after.floors[i]});
  }
  const auto rows = static_cast<Eigen::Index>(out.steps);
  out.time.assign(after.result.time.begin(), after.result.time.begin() + rows);
  out.recorded_response = input.recorded->topRows(rows);
  out.declared_response = before.result.displacement.topRows(rows);
  out.identified_response = after.result.displacement.topRows(rows);
  add_shares(reruns, paths, all, out);
  if (input.clock == "real_time") {
    out.notes.push_back(
        "network paths: their lag is in the re-run only as the actuator paths' "
        "fitted delay (the answers the loop used)");
  }
  return out;
}

}  // namespace rths::identify
