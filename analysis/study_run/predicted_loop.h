// The pre-run verdict of a case with a force predictor (core/force_predictor.h) on any structure:
// the coupled delayed loop of every link with its predictor's model (core::setup_loop_stability).
//
// Inputs:  a case's hybrid setup (its links' delay stages and in-process links), the case, and
//          extra_lag (s) every link also carries (the network a distributed run injects).
// Outputs: CompensatedVerdict: analysed, stable at the links' own lags, the smallest extra lag
//          tolerated (s), relies_on_fit, and one line of text naming each link's critical lag.
// Each link's lag D_a = its delay stages' nominal lag + its in-process link's round trip +
// extra_lag; the model as it starts is the declared specimen times stiffness_factor with its
// dashpot; an online fit whose starting model crosses is judged again with each model fitted to
// its declared specimen (relies_on_fit when that loop is stable).
#pragma once

#include "analysis/study_run/compensated_verdict.h"
#include "core/simulation.h"
#include "rths/proto/config.pb.h"

namespace rths::analysis {

CompensatedVerdict judge_predicted_loop(const core::HybridSetup& setup, const config::Case& c,
                                        double extra_lag);

}  // namespace rths::analysis
