#include "identify/predict.h"

#include <numbers>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/metrics.h"
#include "core/simulation.h"
#include "core/study.h"

namespace rths::identify {
namespace {

std::vector<double> top_displacement(const core::SimulationResult& result) {
  std::vector<double> out(result.steps());
  const auto top = result.displacement.cols() - 1;
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = result.displacement(static_cast<Eigen::Index>(i), top);
  }
  return out;
}

CaseError compare(const std::string& name, const std::vector<double>& reference,
                  const core::SimulationResult& result, double nominal_delay) {
  CaseError e;
  e.name = name;
  e.nominal_delay = nominal_delay;
  e.diverged = result.diverged;
  auto compared = top_displacement(result);
  // A diverged run stops early: compare over the common part, and say so via `diverged`.
  const std::size_t n = std::min(reference.size(), compared.size());
  const std::span<const double> ref(reference.data(), n), cmp(compared.data(), n);
  e.nrmse = core::nrmse(ref, cmp);
  e.paper_eq2 = core::paper_eq2(ref, cmp);
  e.peak_displacement = core::peak_abs(cmp);
  return e;
}

}  // namespace

ActuatorChain actuator_chain(const ChannelModel& model, const SignalScales& scales, double dt) {
  if (model.channel != Channel::kMeasured) {
    throw std::invalid_argument("actuator_chain: needs the model of channel 'measured'");
  }
  ActuatorChain out;
  const auto value = [&](std::optional<Effect> e, const char* name, double fallback) {
    return model.param(e, name, scales).value_or(fallback);
  };
  double delay = value(Effect::kDelay, "delay", 0.0);
  const double gain = value(std::nullopt, "gain", 1.0);
  if (delay < 0.0) {
    out.ignored.push_back("negative delay (lead) of " + std::to_string(delay) + " s, used as 0");
    delay = 0.0;
  }
  std::ostringstream description;
  description << "time shift " << delay * 1e3 << " ms, gain " << gain;
  auto shift = std::make_unique<core::TimeShift>(delay, dt);
  shift->set_gain(gain);
  out.chain.add(std::move(shift));
  for (Effect e : model.effects) {
    switch (e) {
      case Effect::kFirstOrder: {
        const double t = value(e, "time_constant", 0.0);
        out.chain.add(std::make_unique<core::FirstOrderActuator>(t, dt));
        description << ", first order T = " << t * 1e3 << " ms";
        break;
      }
      case Effect::kSecondOrder: {
        const double wn = value(e, "natural_frequency", 0.0);
        const double zeta = value(e, "damping_ratio", 0.0);
        out.chain.add(std::make_unique<core::TransferFunctionStage>(
            std::vector<double>{wn * wn}, std::vector<double>{1.0, 2.0 * zeta * wn, wn * wn}, dt,
            "second-order actuator"));
        description << ", second order fn = " << wn / (2.0 * std::numbers::pi)
                    << " Hz zeta = " << zeta;
        break;
      }
      case Effect::kTimeVaryingDelay:
        out.ignored.push_back("time-varying delay: its mean is used");
        break;
      case Effect::kOffsetDrift:
      case Effect::kBacklash:
      case Effect::kVelocitySaturation:
        out.ignored.push_back(effect_name(e) + ": lab-scale effect, not transferred");
        break;
      default:
        break;
    }
  }
  out.description = description.str();
  return out;
}

StudyPrediction predict_study(const std::filesystem::path& config, const ChannelModel& actuator,
                              const SignalScales& scales) {
  const auto study = core::load_study(config);
  const auto prepared = core::prepare_study(study, config.parent_path());
  StudyPrediction out;
  out.config = config.string();
  const auto& ref_case = core::reference_case(study);
  out.reference_case = ref_case.name();
  const core::HybridSetup reference_setup = core::setup_for_case(prepared, ref_case);
  out.dt = reference_setup.dt;
  const auto reference = top_displacement(core::simulate(reference_setup, prepared.motion));

  for (const auto& c : study.cases()) {
    if (c.name() == ref_case.name()) continue;
    const core::HybridSetup setup = core::setup_for_case(prepared, c);
    const double nominal = setup.delays.empty() ? 0.0 : setup.delays.front().nominal_delay();
    out.cases.push_back(compare(c.name(), reference, core::simulate(setup, prepared.motion), nominal));
  }

  ActuatorChain chain = actuator_chain(actuator, scales, reference_setup.dt);
  out.actuator = chain.description;
  out.ignored = chain.ignored;
  core::HybridSetup setup = prepared.base;
  setup.delays.assign(setup.partition.actuator_storeys.size(), chain.chain);
  out.identified = compare("identified_actuator", reference, core::simulate(setup, prepared.motion),
                           chain.chain.nominal_delay());
  return out;
}

}  // namespace rths::identify
