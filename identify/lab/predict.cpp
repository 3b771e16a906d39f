#include "identify/lab/predict.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "core/metrics.h"
#include "core/simulation.h"
#include "identify/model/study_config.h"
#include "study/stability_config.h"
#include "study/study.h"

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
  e.peak_error_pct = core::relative_peak_error_pct(ref, cmp);
  e.rms_error_pct = core::relative_rms_error_pct(ref, cmp);
  e.nrmse = core::nrmse(ref, cmp);
  e.paper_eq2 = core::paper_eq2(ref, cmp);
  e.peak_displacement = core::peak_abs(cmp);
  return e;
}

// "time shift 4.6 ms, gain 1, first order T = 21.8 ms, second order fn = 12 Hz zeta = 0.7".
std::string describe_stages(const config::Case& study_case) {
  std::ostringstream out;
  for (const auto& stage : study_case.delay()) {
    if (stage.has_shift()) {
      const double gain = stage.amplitude_gain() == 0.0 ? 1.0 : stage.amplitude_gain();
      out << "time shift " << stage.shift().delay() * 1e3 << " ms, gain " << gain;
    } else if (stage.has_first_order()) {
      out << ", first order T = " << stage.first_order().time_constant() * 1e3 << " ms";
    } else if (stage.has_transfer_function() && stage.transfer_function().denominator_size() == 3) {
      const auto& den = stage.transfer_function().denominator();
      const double wn = std::sqrt(den[2]);
      out << ", second order fn = " << wn / (2.0 * std::numbers::pi)
          << " Hz zeta = " << den[1] / (2.0 * wn);
    }
  }
  return out.str();
}

}  // namespace

ActuatorChain actuator_chain(const ChannelModel& model, const SignalScales& scales, double dt) {
  if (model.channel != Channel::kMeasured) {
    throw std::invalid_argument("actuator_chain: needs the model of channel 'measured'");
  }
  // The one translation of effects into stages is the study config's (study_config.h).
  const ActuatorCase study_case = actuator_case(model, scales);
  ActuatorChain out;
  out.chain = study::make_delay_chain(study_case.study_case.delay(), dt, {});
  out.description = describe_stages(study_case.study_case);
  out.ignored = study_case.left_out;
  return out;
}

StudyPrediction predict_study(const std::filesystem::path& config, const ChannelModel& actuator,
                              const SignalScales& scales) {
  const auto study = study::load_study(config);
  const auto prepared = study::prepare_study(study, config.parent_path());
  StudyPrediction out;
  out.config = config.string();
  const auto& ref_case = study::reference_case(study);
  out.reference_case = ref_case.name();
  const core::HybridSetup reference_setup = study::setup_for_case(prepared, ref_case);
  out.dt = reference_setup.dt;
  const auto reference = top_displacement(core::simulate(reference_setup, prepared.motion));

  for (const auto& c : study.cases()) {
    if (c.name() == ref_case.name()) continue;
    const core::HybridSetup setup = study::setup_for_case(prepared, c);
    const double nominal = setup.delays.empty() ? 0.0 : setup.delays.front().nominal_delay();
    out.cases.push_back(
        compare(c.name(), reference, core::simulate(setup, prepared.motion), nominal));
  }

  ActuatorChain chain = actuator_chain(actuator, scales, reference_setup.dt);
  out.actuator = chain.description;
  out.ignored = chain.ignored;
  core::HybridSetup setup = prepared.base;
  setup.delays.assign(setup.partition.actuator_storeys.size(), chain.chain);
  out.identified = compare("identified_actuator", reference, core::simulate(setup, prepared.motion),
                           chain.chain.nominal_delay());
  out.stability = study::check_lag_critical_delay(prepared, chain.chain.nominal_delay());
  return out;
}

}  // namespace rths::identify
