#pragma once
// Putting the identified actuator back into a simulation: the lab's actuator, as fitted from its
// record, replaces the declared delay stages of a study config, and the in-process hybrid
// simulation (core::simulate) predicts how far the test will stray from the reference.
//
// The actuator channel model becomes a core::DelayChain made (study::make_delay_chain) from the
// stages study_config.h's actuator_case writes, the one translation of effects into stages: what
// --predict simulates is what --out writes for `rths run`, and what a study cannot hold (offsets,
// backlash, saturation, the stroke limit, drifts' variation, a lead) is listed in `ignored`.
// Error measures (core/metrics.h) on the displacement of the top degree of freedom against the
// reference case's, e = u - u_ref: E_peak = 100 max|e| / max|u_ref| and E_rms = 100
// sqrt(sum e^2 / sum u_ref^2) (%), which every rths output leads with; the paper's nrmse
// (sqrt(mean e^2) / median |u_ref|, relative) and paper_eq2 (its Eq. 2 as printed).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/delay.h"
#include "core/stability.h"
#include "identify/model/model.h"

namespace rths::identify {

struct ActuatorChain {
  core::DelayChain chain;
  std::string description;
  std::vector<std::string> ignored;
};
// @pre model.channel == Channel::kMeasured. Throws std::invalid_argument otherwise.
ActuatorChain actuator_chain(const ChannelModel& model, const SignalScales& scales, double dt);

struct CaseError {
  std::string name;
  double nominal_delay = 0.0;                                    // s, the chain's low-frequency lag
  double peak_error_pct = 0.0, rms_error_pct = 0.0;              // E_peak, E_rms (%)
  double nrmse = 0.0, paper_eq2 = 0.0, peak_displacement = 0.0;  // -, -, m
  bool diverged = false;
};

struct StudyPrediction {
  std::string config, reference_case;
  double dt = 0.0;
  CaseError identified;          // the identified actuator on every experimental storey
  std::vector<CaseError> cases;  // the config's own cases, for comparison
  std::string actuator;          // description of the chain
  std::vector<std::string> ignored;
  // The identified actuator's lag against the study's critical delay (study/stability_config.h, the one
  // pre-run judgement): the margin, the verdict and the lag the test could take. Empty when the
  // study has no experimental part.
  std::optional<core::CriticalDelayCheck> stability;
};

// Throws what load_study/prepare_study/simulate throw (std::invalid_argument naming the config).
StudyPrediction predict_study(const std::filesystem::path& config, const ChannelModel& actuator,
                              const SignalScales& scales);

}  // namespace rths::identify
