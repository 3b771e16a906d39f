// The study's summary as JSON and as text (analysis/study_run/study_run.h: error_measures_json,
// study_summary_json, study_summary_text).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "analysis/study_run/study_run.h"
#include "core/time_text.h"
#include "util/text_table.h"

namespace rths::analysis {

namespace {}  // namespace

namespace {

nlohmann::json compensated_json(const std::optional<CompensatedVerdict>& v) {
  if (!v) return nullptr;
  return {{"analysed", v->analysed},
          {"stable", v->analysed ? nlohmann::json(v->stable) : nlohmann::json()},
          {"extra_delay_tolerated_s",
           v->extra_delay_tolerated ? nlohmann::json(*v->extra_delay_tolerated) : nlohmann::json()},
          {"verdict", v->text}};
}

// Per predicted actuator, in config order: the RMS and peak of its prediction error (N) over the
// steps run, the RMS against the measured force's RMS (%), and its model at the run's end with
// the terms' standard errors (ForcePredictor::model_text; empty when the run did not keep it).
struct PredictionErrorSummary {
  int actuator = 0;  // 1-based index (channel order, as a HOLD names it)
  std::string name;  // its site, or its channel (actuator_names.h)
  double rms = 0.0, peak = 0.0, relative_pct = 0.0;
  std::string model;
};

std::vector<PredictionErrorSummary> prediction_errors(const CaseOutcome& c,
                                                      const ActuatorNames& names) {
  std::vector<PredictionErrorSummary> out;
  const core::Mat& e = c.simulation.prediction_error;
  const core::Mat& f = c.simulation.measured_force;
  std::vector<int> predicted;
  for (int a : names.order)
    if (std::find(c.predicted_actuators.begin(), c.predicted_actuators.end(), a) !=
        c.predicted_actuators.end())
      predicted.push_back(a);
  for (int a : c.predicted_actuators)
    if (std::find(predicted.begin(), predicted.end(), a) == predicted.end()) predicted.push_back(a);
  for (int a : predicted) {
    if (a >= e.cols() || e.rows() == 0) continue;
    PredictionErrorSummary s;
    s.actuator = a + 1;
    s.name = names.of(a);
    const double rows = static_cast<double>(e.rows());
    s.rms = std::sqrt(e.col(a).squaredNorm() / rows);
    s.peak = e.col(a).cwiseAbs().maxCoeff();
    const double force_rms = std::sqrt(f.col(a).squaredNorm() / rows);
    s.relative_pct = force_rms > 0 ? 100.0 * s.rms / force_rms : 0.0;
    const auto& models = c.simulation.predictor_models;
    if (static_cast<std::size_t>(a) < models.size()) s.model = models[static_cast<std::size_t>(a)];
    out.push_back(s);
  }
  return out;
}

// The critical-delay check of a case in summary.json; null without an experimental part.
nlohmann::json stability_json(const std::optional<core::CriticalDelayCheck>& check) {
  if (!check) return nullptr;
  const auto& s = *check;
  const auto opt = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json();
  };
  return {
      {"lag_s", s.lag},
      {"continuous_critical_delay_s", opt(s.continuous)},
      {"discrete_critical_delay_s", opt(s.discrete)},
      {"discrete_check", s.discrete_skipped.empty() ? "made" : "skipped: " + s.discrete_skipped},
      {"critical_delay_s", opt(s.critical())},
      {"margin_pct", s.critical() ? nlohmann::json(100.0 * s.margin()) : nlohmann::json()},
      {"past_critical_delay", s.past()},
      {"assumed", s.assumed}};
}

// Per linked actuator, in config order, what its answers did over the record (Case.link).
nlohmann::json link_answers_json(const CaseOutcome& c, const ActuatorNames& names) {
  if (c.link_answers.empty()) return nullptr;
  nlohmann::json out = nlohmann::json::array();
  for (int a : names.order) {
    if (a >= static_cast<int>(c.link_answers.size())) continue;
    const core::LinkAnswerStats& s = c.link_answers[static_cast<std::size_t>(a)];
    out.push_back({{"actuator", a + 1},
                   {"name", names.of(a)},
                   {"used_answers", s.used_answers},
                   {"unused_answers", s.unused_answers},
                   {"repeated_steps", s.repeated_steps},
                   {"median_age_steps", s.median_age},
                   {"max_age_steps", s.max_age}});
  }
  return out;
}

// One line per linked actuator: the answers the integrator used, those it never used, and
// their age, as the DDS run's line counts them.
void write_link_lines(std::ostream& out, const CaseOutcome& c, const ActuatorNames& names) {
  for (int a : names.order) {
    if (a >= static_cast<int>(c.link_answers.size())) continue;
    const core::LinkAnswerStats& s = c.link_answers[static_cast<std::size_t>(a)];
    const auto ms = [&](std::int64_t steps) {
      return core::format_ms(static_cast<double>(steps) * c.simulation.dt);
    };
    out << c.name << ": link to " << names.of(a) << ": " << s.used_answers
        << " answers used (each step uses the newest arrived), " << s.unused_answers
        << " never used (lost, or overtaken within a step), " << s.repeated_steps
        << " steps kept the step before's; age median " << s.median_age << " steps ("
        << ms(s.median_age) << "), max " << s.max_age << " (" << ms(s.max_age) << ")\n";
  }
}

nlohmann::json prediction_error_json(const CaseOutcome& c, const ActuatorNames& names) {
  if (c.predicted_actuators.empty()) return nullptr;
  nlohmann::json out = nlohmann::json::array();
  for (const PredictionErrorSummary& s : prediction_errors(c, names))
    out.push_back({{"actuator", s.actuator},
                   {"name", s.name},
                   {"rms_n", s.rms},
                   {"peak_n", s.peak},
                   {"rms_of_measured_force_pct", s.relative_pct},
                   {"model", s.model.empty() ? nlohmann::json() : nlohmann::json(s.model)}});
  return out;
}

nlohmann::json growth_json(const std::optional<core::EnvelopeGrowth>& g) {
  if (!g) return nullptr;
  return {{"grows", g->grows()},
          {"rate_per_s", g->rate},
          {"doubling_time_s", g->rate > 0.0 ? nlohmann::json(g->doubling_time) : nlohmann::json()},
          {"r_squared", g->r_squared},
          {"cycles", g->windows},
          {"cycle_s", g->period},
          {"span_s", g->span}};
}

}  // namespace

nlohmann::json error_measures_json() {
  return {{"peak_error_pct", kPeakErrorDefinition},
          {"rms_error_pct", kRmsErrorDefinition},
          {"peak_error_m", "max|u - u_ref| (m)"},
          {"nrmse_pct",
           "the paper's normalisation: 100 sqrt(mean (u - u_ref)^2) / median|u_ref| (%); a record "
           "ending in near-zero motion has a tiny median and inflates it"},
          {"paper_eq2_as_printed",
           "the paper's Eq. 2 as printed: sqrt(sum (u - u_ref)^2) / N / "
           "median|u_ref| (shrinks like 1/sqrt(N))"}};
}

nlohmann::json study_summary_json(const StudyOutcome& outcome) {
  nlohmann::json cases = nlohmann::json::array();
  for (const CaseOutcome& c : outcome.cases) {
    // A case that stopped early has no error over the steps it did not run: its errors are null,
    // and those over the steps it covered are given apart, named as such.
    const bool covers = c.comparison.covers_reference();
    const auto whole = [covers](double v) { return covers ? nlohmann::json(v) : nlohmann::json(); };
    const nlohmann::json covered =
        covers ? nlohmann::json()
               : nlohmann::json{{"steps", c.comparison.steps_compared},
                                {"peak_error_pct", c.comparison.peak_error_pct},
                                {"rms_error_pct", c.comparison.rms_error_pct},
                                {"peak_error_m", c.comparison.peak_error_m}};
    cases.push_back({{"name", c.name},
                     {"delay", c.delay_description},
                     {"nominal_delay_s", c.nominal_delay},
                     {"status", c.status},
                     {"status_detail", c.status_detail},
                     {"expect_unstable", c.expect_unstable},
                     {"stability", stability_json(c.stability)},
                     {"compensated_loop", compensated_json(c.compensated)},
                     {"prediction_error", prediction_error_json(c, outcome.actuators)},
                     {"link_answers", link_answers_json(c, outcome.actuators)},
                     {"envelope_growth", growth_json(c.growth)},
                     {"peak_displacement_m", c.comparison.peak_m},
                     {"peak_error_pct", whole(c.comparison.peak_error_pct)},
                     {"rms_error_pct", whole(c.comparison.rms_error_pct)},
                     {"peak_error_m", whole(c.comparison.peak_error_m)},
                     {"paper_eq2_as_printed", whole(c.comparison.paper_eq2_as_printed)},
                     {"nrmse_pct", whole(c.comparison.nrmse_pct)},
                     {"steps_compared", c.comparison.steps_compared},
                     {"reference_steps", c.comparison.reference_steps},
                     {"errors_over_covered_steps", covered},
                     {"diverged", c.diverged()},
                     {"steps", c.simulation.steps()}});
  }
  return {{"study", outcome.study_name},
          {"measures", error_measures_json()},
          {"motion_units", outcome.motion_units},
          {"motion", outcome.motion_description},
          {"response", outcome.response.describe()},
          {"reference_case", outcome.reference().name},
          {"reference", outcome.reference_description()},
          {"lag_free_peak_m", outcome.lag_free_peak},
          {"cases", cases}};
}

namespace {

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

// The row of one case: errors of a response that grew without bound measure nothing (the JSON
// keeps them), so a diverged case shows "-" there.
// The margin cell: the lag's margin against the critical delay; for a compensated case, the
// compensated loop's verdict in short (the lag it tolerates beyond its own, "unstable", or "n/a"
// when it is not analysable), spelled out with the uncompensated margin below the table.
std::string margin_cell(const CaseOutcome& c) {
  if (c.compensated) {
    const CompensatedVerdict& v = *c.compensated;
    if (!v.analysed) return "n/a [comp.]";
    if (!v.stable) return "unstable [comp.]";
    if (v.relies_on_fit) return "needs fit [comp.]";
    if (!v.extra_delay_tolerated) return "stable";
    std::string cell =
        "+";  // appended, not `"+" + core::format_ms(...)`: GCC 12 -O3 warns falsely on that
    cell += core::format_ms(*v.extra_delay_tolerated);
    return cell + " [comp.]";
  }
  if (c.stability && c.stability->critical()) return fixed(100.0 * c.stability->margin(), 1) + " %";
  return "-";
}

// Errors only for a case that stayed bounded and covered the whole reference: a case that stopped
// early has no error over the steps it did not run ("-", and a line below with the steps it did).
std::vector<std::string> summary_row(const CaseOutcome& c) {
  std::string critical = "-";
  if (c.stability)
    critical = c.stability->critical() ? core::format_ms(*c.stability->critical()) : "none";
  const std::string margin = margin_cell(c);
  const bool measured = !c.diverged() && c.comparison.covers_reference();
  return {c.name,
          c.delay_description,
          fixed(c.comparison.peak_m * 1e3, 3),
          measured ? fixed(c.comparison.peak_error_pct, 2) : "-",
          measured ? fixed(c.comparison.rms_error_pct, 2) : "-",
          measured ? fixed(c.comparison.peak_error_m * 1e3, 3) : "-",
          critical,
          margin,
          c.status + (c.diverged() && c.expect_unstable ? " (expected)" : "")};
}

}  // namespace

std::string study_summary_text(const StudyOutcome& outcome) {
  std::ostringstream out;
  out << "study: " << outcome.study_name << " (every case against "
      << outcome.reference_description() << "; response: " << outcome.response.describe()
      << " displacement; motion read in " << outcome.motion_units << ")\n";
  if (!outcome.motion_description.empty()) out << "motion: " << outcome.motion_description << "\n";
  using Align = util::TextTable::Align;
  util::TextTable table({{"case", Align::kLeft, 40},
                         {"delay", Align::kLeft, 28},
                         {"peak (mm)", Align::kRight},
                         {"E_peak (%)", Align::kRight},
                         {"E_rms (%)", Align::kRight},
                         {"peak err (mm)", Align::kRight},
                         {"crit. delay", Align::kRight},
                         {"margin", Align::kRight},
                         {"status", Align::kLeft, 40}});
  for (const CaseOutcome& c : outcome.cases) table.add_row(summary_row(c));
  out << table.render();
  out << "E_peak: " << kPeakErrorDefinition << "; E_rms: " << kRmsErrorDefinition
      << "; the paper's median-normalised NRMSE and Eq. 2 are in summary.json\n";
  for (const CaseOutcome& c : outcome.cases) {
    if (c.diverged() || c.comparison.covers_reference()) continue;
    out << c.name << ": stopped at step " << c.comparison.steps_compared << " of "
        << c.comparison.reference_steps << ": no error over the steps it did not run; over its "
        << c.comparison.steps_compared << " steps E_peak " << fixed(c.comparison.peak_error_pct, 2)
        << " %, E_rms " << fixed(c.comparison.rms_error_pct, 2) << " %\n";
  }
  if (std::any_of(outcome.cases.begin(), outcome.cases.end(),
                  [](const CaseOutcome& c) { return c.compensated.has_value(); }))
    out << "margin [comp.]: the compensated loop's, as the lag it tolerates beyond its own (n/a: "
           "not analysable before the run; needs fit: unstable with the predictor's model as it "
           "starts, stable once fitted to the declared specimen); each such case's line below "
           "gives it with the uncompensated margin\n";
  for (const CaseOutcome& c : outcome.cases) {
    if (!c.status_detail.empty()) out << c.name << ": " << c.status_detail << "\n";
    if (c.compensated) out << c.name << ": " << c.compensated->text << "\n";
    write_link_lines(out, c, outcome.actuators);
    for (const PredictionErrorSummary& p : prediction_errors(c, outcome.actuators))
      out << c.name << ": prediction error at " << p.name << " (actuator " << p.actuator
          << "): RMS " << fixed(p.rms, 2) << " N (" << fixed(p.relative_pct, 2)
          << " % of the measured force's RMS), peak " << fixed(p.peak, 2) << " N"
          << (p.model.empty() ? "" : "; its model at the end: " + p.model) << "\n";
  }
  return out.str();
}

}  // namespace rths::analysis
