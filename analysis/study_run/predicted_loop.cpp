#include "analysis/study_run/predicted_loop.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "core/coupled_stability.h"
#include "core/time_text.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

// One link's limit in a verdict: "critical lag 107 ms against the case's 74 ms: stable, tolerates
// 33.2 ms more", "... PAST it", or "stable for every lag"; `whose` names the lag compared.
std::string link_limit_text(const std::optional<double>& critical, double lag,
                            const std::string& whose) {
  std::ostringstream text;
  text << std::setprecision(3);
  if (!critical) return "stable for every lag";
  text << "critical lag " << 1e3 * *critical << " ms against " << whose << " " << 1e3 * lag
       << " ms: ";
  if (lag < *critical)
    text << "stable, tolerates " << 1e3 * (*critical - lag) << " ms more";
  else
    text << "PAST it";
  return text.str();
}

// The coupled verdict's text: one link alone, or every link alike and then each one with the
// others at their lags (core::CoupledLoopStability).
std::string coupled_links_text(const core::CoupledLoopStability& loop,
                               const core::HybridSetup& setup, const std::vector<double>& lags) {
  const auto& storeys = setup.partition.actuator_storeys;
  if (lags.size() == 1) return link_limit_text(loop.parts[0].critical_lag, lags[0], "the case's");
  std::ostringstream text;
  text << std::setprecision(3);
  const double largest = *std::max_element(lags.begin(), lags.end());
  text << "every link alike, "
       << link_limit_text(loop.common_critical_lag, largest, "the largest link's") << "; "
       << (loop.stable ? "stable" : "UNSTABLE") << " at the links' own lags";
  if (!loop.stable)
    text << " (the link of "
         << setup.partition.channel_name(storeys[static_cast<std::size_t>(loop.crossed)])
         << " crosses at " << 1e3 * loop.crossed_at << " ms)";
  text << "; each link, the others at theirs:";
  for (std::size_t a = 0; a < lags.size(); ++a) {
    const core::PartLimit& part = loop.parts[a];
    text << (a ? "; " : " ") << setup.partition.channel_name(storeys[a]) << " ";
    if (part.crossed_before >= 0)
      text << "none (the loop crosses before it lags)";
    else
      text << link_limit_text(part.critical_lag, lags[a], "its");
  }
  return text.str();
}

// The smallest extra lag (s) the loop tolerates: every link's together beyond the largest, or one
// link's beyond its own; empty when no limit exists.
std::optional<double> tolerated_extra_lag(const core::CoupledLoopStability& loop,
                                          const std::vector<double>& lags) {
  std::optional<double> out;
  const auto keep = [&out](double extra) { out = out ? std::min(*out, extra) : extra; };
  if (loop.common_critical_lag)
    keep(*loop.common_critical_lag - *std::max_element(lags.begin(), lags.end()));
  for (std::size_t a = 0; a < lags.size(); ++a)
    if (loop.parts[a].critical_lag) keep(*loop.parts[a].critical_lag - lags[a]);
  return out;
}

// An online fit's loop whose starting model crosses: the same loop with each predictor fitted to
// its declared specimen. Stable there, the verdict is the fitted loop's and relies on the fit.
void judge_fitted_loop(const core::HybridSetup& setup, const std::vector<double>& lags,
                       CompensatedVerdict& verdict, std::ostringstream& text) {
  const core::CoupledLoopStability fitted =
      core::setup_loop_stability(setup, lags, core::PredictorModels::kFittedToTheDeclaredSpecimen);
  text << "; fitted to the declared specimen: " << coupled_links_text(fitted, setup, lags);
  if (!fitted.stable) return;
  verdict.stable = true;
  verdict.relies_on_fit = true;
  verdict.extra_delay_tolerated = tolerated_extra_lag(fitted, lags);
  text << ", so the run relies on the online fit converging before the response grows (the "
          "predictor's bound, max_relative_error, HOLDs it if not)";
}

}  // namespace

// The pre-run verdict of a case with a force predictor (core/force_predictor.h): the coupled loop
// of every link with its predictor's model as it starts (the declared specimen times
// stiffness_factor, its dashpot; core::setup_loop_stability, any number of DOFs and links),
// each link at its delay stages' lag and its link's round trip plus `extra_lag` (s).
CompensatedVerdict judge_predicted_loop(const core::HybridSetup& setup, const config::Case& c,
                                        double extra_lag) {
  CompensatedVerdict verdict;
  const config::ForcePredictor& block = c.force_predictor();
  const double factor = study::predictor_stiffness_factor(block);
  std::ostringstream text;
  text << std::setprecision(3) << "force predictor (model stiffness " << std::showpos
       << 100.0 * (factor - 1.0) << std::noshowpos << " %"
       << (block.fixed_model() ? ", fixed" : ", fitted online") << "): ";
  // Each link's measured pair: its delay stages, its in-process link's round trip, extra_lag.
  std::vector<double> lags;
  for (std::size_t a = 0; a < setup.partition.actuator_storeys.size(); ++a)
    lags.push_back((a < setup.delays.size() ? setup.delays[a].nominal_delay() : 0.0) +
                   (a < setup.links.size() ? core::nominal_round_trip(setup.links[a]) : 0.0) +
                   extra_lag);
  if (lags.empty()) {
    verdict.text = text.str() + "no experimental part: nothing comes back late";
    return verdict;
  }
  const core::CoupledLoopStability loop = core::setup_loop_stability(setup, lags);
  verdict.analysed = true;
  verdict.stable = loop.stable;
  if (loop.stable) verdict.extra_delay_tolerated = tolerated_extra_lag(loop, lags);
  text << coupled_links_text(loop, setup, lags);
  if (!block.fixed_model()) {
    text << " (the model as it starts; the online fit shrinks its error)";
    if (!loop.stable) judge_fitted_loop(setup, lags, verdict, text);
  }
  text << " [" << loop.assumed << "]";
  verdict.text = text.str();
  return verdict;
}

}  // namespace rths::analysis
