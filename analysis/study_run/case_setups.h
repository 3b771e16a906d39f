#pragma once
// Each case's setup of a study, built once (study::setup_for_case) and held for its run, with
// one copy of the structural model held among them (a compensated case's verdict builds one
// more, briefly, for its uncompensated twin: analysis/study_run/study_run.cpp). setup_for_case copies the base setup's model
// (at 2,000 DOFs its dense M, C and K: about 100 MB) and changes only the case's delays,
// compensators, force predictors and links, never the model; so every setup here but the one
// lent out is held without its model, and the one model (the last case's own copy) goes to the
// case that asks for it. Each case's loop (its experimental parts, no lags, and its lag: what
// the critical-delay check needs of it) is taken while its setup is built. A case whose setup
// changed the model (its size or sparsity) is refused: std::logic_error naming it.
// Inputs: a prepared study, its cases (each alive as long as this), the extra lag (s) added to
// each case's answer lag.

#include <cstddef>
#include <vector>

#include "core/coupled_stability.h"
#include "core/simulation.h"
#include "study/study.h"

namespace rths::analysis {

// A case's loop as the critical-delay check sees it: its parts (no lags), its lag (s).
struct CaseLoop {
  std::vector<core::DelayedPart> parts;
  double lag = 0.0;  // s: the case's answer lag (study::answer_lag) plus the extra lag
};

CaseLoop case_loop(const core::HybridSetup& setup, double extra_lag);

class CaseSetups {
 public:
  CaseSetups(const study::PreparedStudy& prepared, const std::vector<const config::Case*>& cases,
             double extra_lag);

  // Each case's loop, in the order given.
  const std::vector<CaseLoop>& loops() const { return loops_; }
  // Case i's setup with the model, valid until the next call (which takes the model back).
  const core::HybridSetup& lend(std::size_t i);

 private:
  std::vector<core::HybridSetup> setups_;  // each without its model but the one lent
  std::vector<CaseLoop> loops_;
  std::size_t lent_;  // the case holding the model
};

}  // namespace rths::analysis
