#include "analysis/study_run.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <span>
#include <iomanip>
#include <sstream>

#include "analysis/atomic_file.h"
#include "analysis/plot.h"
#include "core/metrics.h"

namespace rths::analysis {
namespace {

std::vector<double> top_floor(const core::SimulationResult& result) {
  const auto column = result.displacement.cols() - 1;
  std::vector<double> response(result.steps());
  for (std::size_t k = 0; k < response.size(); ++k) response[k] = result.displacement(static_cast<Eigen::Index>(k), column);
  return response;
}

}  // namespace

StudyOutcome run_study(const core::PreparedStudy& prepared) {
  const config::Study& study = prepared.config;
  config::Study with_cases = study;
  if (with_cases.cases_size() == 0) with_cases.add_cases()->set_name("reference");
  const config::Case& reference = core::reference_case(with_cases);

  StudyOutcome outcome;
  outcome.study_name = study.name();
  for (int i = 0; i < with_cases.cases_size(); ++i) {
    const config::Case& study_case = with_cases.cases(i);
    if (&study_case == &reference) outcome.reference_index = static_cast<std::size_t>(i);
    core::HybridSetup setup = core::setup_for_case(prepared, study_case);
    CaseOutcome result;
    result.name = study_case.name().empty() ? "case" + std::to_string(i) : study_case.name();
    if (!setup.delays.empty()) {
      result.delay_description = setup.delays.front().describe();
      result.nominal_delay = setup.delays.front().nominal_delay();
    } else {
      result.delay_description = "no experimental substructure";
    }
    result.simulation = core::simulate(setup, prepared.motion);
    result.response = top_floor(result.simulation);
    result.peak = core::peak_abs(result.response);
    outcome.cases.push_back(std::move(result));
  }
  const std::vector<double>& ref = outcome.cases[outcome.reference_index].response;
  for (CaseOutcome& c : outcome.cases) {
    // A diverged case stops early; compare over the steps it has, and say so via `diverged`.
    const std::size_t n = std::min(ref.size(), c.response.size());
    const std::span<const double> r(ref.data(), n), x(c.response.data(), n);
    c.paper_eq2 = core::paper_eq2(r, x);
    c.nrmse = core::nrmse(r, x);
    c.peak_error = core::peak_error(r, x);
  }
  return outcome;
}

void write_study_plots(const StudyOutcome& outcome, const std::filesystem::path& directory) {
  std::filesystem::create_directories(directory);
  PlotSpec displacement{outcome.study_name + ": top-floor displacement", "time (s)", "displacement (mm)", {}};
  PlotSpec loop{outcome.study_name + ": what the integrator sees (experimental part)",
                "commanded displacement (mm)", "measured force (kN)", {}};
  for (const CaseOutcome& c : outcome.cases) {
    Series s{c.name, c.simulation.time, {}};
    for (double u : c.response) s.y.push_back(u * 1e3);
    displacement.series.push_back(std::move(s));
    if (c.simulation.command.cols() > 0) {
      Series l{c.name, {}, {}};
      for (Eigen::Index k = 0; k < c.simulation.command.rows(); ++k) {
        l.x.push_back(c.simulation.command(k, 0) * 1e3);
        l.y.push_back(c.simulation.measured_force(k, 0) * 1e-3);
      }
      loop.series.push_back(std::move(l));
    }
  }
  write_png_plot(displacement, directory / "displacement.png");
  if (!loop.series.empty()) write_png_plot(loop, directory / "force_displacement.png");
}

nlohmann::json study_summary_json(const StudyOutcome& outcome) {
  nlohmann::json cases = nlohmann::json::array();
  for (const CaseOutcome& c : outcome.cases) {
    cases.push_back({{"name", c.name},
                     {"delay", c.delay_description},
                     {"nominal_delay_s", c.nominal_delay},
                     {"peak_displacement_m", c.peak},
                     {"paper_eq2_as_printed", c.paper_eq2},
                     {"nrmse", c.nrmse},
                     {"peak_error_m", c.peak_error},
                     {"diverged", c.simulation.diverged},
                     {"steps", c.simulation.steps()}});
  }
  return {{"study", outcome.study_name},
          {"reference_case", outcome.cases[outcome.reference_index].name},
          {"cases", cases}};
}

std::string study_summary_text(const StudyOutcome& outcome) {
  std::ostringstream out;
  out << "study: " << outcome.study_name << " (reference: " << outcome.cases[outcome.reference_index].name << ")\n";
  out << std::left << std::setw(26) << "case" << std::setw(36) << "delay" << std::right
      << std::setw(12) << "peak (mm)" << std::setw(12) << "NRMSE" << std::setw(16) << "Eq.2 (paper)"
      << std::setw(16) << "peak err (mm)" << "\n";
  for (const CaseOutcome& c : outcome.cases) {
    out << std::left << std::setw(26) << c.name << std::setw(36) << c.delay_description << std::right
        << std::fixed << std::setprecision(3) << std::setw(12) << c.peak * 1e3 << std::setw(12)
        << c.nrmse << std::setprecision(5) << std::setw(16) << c.paper_eq2 << std::setprecision(3)
        << std::setw(16) << c.peak_error * 1e3 << (c.simulation.diverged ? "  DIVERGED" : "") << "\n";
  }
  return out.str();
}

}  // namespace rths::analysis
