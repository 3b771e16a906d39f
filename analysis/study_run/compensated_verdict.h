// A compensated case's verdict before it runs, one struct for every kind of compensation: the
// polynomial and model-based compensators (analysis/study_run/study_run.h, judge_compensated_loop) and the
// force predictor's coupled loop (analysis/study_run/predicted_loop.h). Units: seconds.
#pragma once

#include <optional>
#include <string>

namespace rths::analysis {

// Pre-run verdict on a compensated case's loop. Linear compensators (polynomial, model-based
// without an adaptive correction) are analysed with core::compensated_stability: exactly on a
// one-storey loop; on several DOFs by the modal approximation (each mode of (M, K) with
// experimental stiffness an SDOF with its modal damping and experimental fraction, the loop
// unstable when any mode is, the smallest margin kept), which the text states. An adaptive one
// (ATS, an adaptive correction) changes its coefficients during the run and cannot be judged
// before it, which the text says, with the uncompensated lag's check beside. A case with several
// compensators (several actuators) is not analysed.
struct CompensatedVerdict {
  bool analysed = false;  // false: adaptive, or a structure the analysis does not cover
  bool stable = false;    // analysed and stable as configured (meaningful when analysed)
  std::optional<double> extra_delay_tolerated;  // s, analysed and stable: the smaller margin
  // A force predictor fitted online whose model as it starts makes the loop cross, where the
  // model fitted to the declared specimen does not: `stable` is the fitted model's, and the run
  // relies on the fit converging before the response grows (its bound HOLDs it if not).
  bool relies_on_fit = false;
  std::string
      text;  // one line, e.g. "compensated loop (polynomial): stable, tolerates 9.1 ms more"
};

}  // namespace rths::analysis
