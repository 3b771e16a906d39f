#include "analysis/benchmark_evaluation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "core/structure_response.h"

namespace rths::analysis {
namespace {

std::vector<double> column(const core::Mat& m, Eigen::Index c) {
  std::vector<double> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) out[static_cast<std::size_t>(i)] = m(i, c);
  return out;
}

// "J1 (ms) J2 ... J9 (%)" values of one row, J1 in ms.
std::string row(const std::string& name, const std::array<double, 9>& j) {
  char buffer[64];
  std::string out = name;
  out.resize(std::max<std::size_t>(out.size() + 1, 24), ' ');
  for (double v : j) {
    std::snprintf(buffer, sizeof buffer, "%8.2f", v);
    out += buffer;
  }
  return out + "\n";
}

}  // namespace

std::optional<BenchmarkEvaluation> evaluate_benchmark(const core::PreparedStudy& prepared,
                                                      const StudyOutcome& outcome) {
  const config::Study& study = prepared.config;
  if (!study.has_benchmark()) return std::nullopt;
  const config::BenchmarkEvaluation& spec = study.benchmark();
  const core::StructuralModel whole = core::make_structure(study.structure(), prepared.base_dir);
  const int dof = spec.experimental_dof() == 0 ? 0 : spec.experimental_dof() - 1;
  if (dof < 0 || dof >= whole.dofs())
    throw std::invalid_argument(
        "benchmark.experimental_dof: " + std::to_string(spec.experimental_dof()) +
        " is outside 1.." + std::to_string(whole.dofs()));
  if (spec.published_size() != 0 && spec.published_size() != 9)
    throw std::invalid_argument("benchmark.published: " + std::to_string(spec.published_size()) +
                                " values, J1-J9 are 9");
  BenchmarkEvaluation out;
  out.dt = prepared.motion.dt;
  out.published.assign(spec.published().begin(), spec.published().end());
  out.published_case = spec.published_case();
  out.published_source = spec.published_source();
  const core::LinearResponse reference = core::exact_linear_response(whole, prepared.motion);
  const double j1_search = spec.j1_search() > 0 ? spec.j1_search() : 49 * out.dt;
  for (std::size_t i = 0; i < outcome.cases.size(); ++i) {
    const CaseOutcome& c = outcome.cases[i];
    if (i == outcome.reference_index || c.simulation.command.cols() == 0) continue;
    const auto actuator = std::find(prepared.base.partition.actuator_storeys.begin(),
                                    prepared.base.partition.actuator_storeys.end(), dof) -
                          prepared.base.partition.actuator_storeys.begin();
    if (actuator >= c.simulation.command.cols())
      throw std::invalid_argument("benchmark.experimental_dof: DOF " + std::to_string(dof + 1) +
                                  " is not experimental");
    const std::vector<double> target = column(c.simulation.command, actuator);
    const std::vector<double> measured = column(c.simulation.realised, actuator);
    out.cases.push_back(
        {c.name, core::benchmark_criteria(target, measured, c.simulation.displacement,
                                          reference.displacement, dof, out.dt, j1_search)});
  }
  return out;
}

std::string benchmark_table(const BenchmarkEvaluation& e) {
  std::ostringstream out;
  out << "RTHS benchmark criteria (J1 ms, J2-J9 %), against the exact response of the whole "
         "structure\n";
  out << std::string(24, ' ')
      << "      J1      J2      J3      J4      J5      J6      J7      J8      J9\n";
  std::array<double, 9> published{};
  if (!e.published.empty()) {
    std::copy(e.published.begin(), e.published.end(), published.begin());
    out << row("published (" + e.published_case + ")", published);
  }
  for (const BenchmarkCaseCriteria& c : e.cases) {
    std::array<double, 9> j = c.criteria.j;
    j[0] *= 1e3;
    out << row(c.name, j);
    if (e.published.empty()) continue;
    std::array<double, 9> difference{};
    difference[0] = (j[0] - published[0]) * 1e-3 / e.dt;  // samples
    for (std::size_t k = 1; k < 9; ++k)
      difference[k] = 100.0 * (j[k] - published[k]) / published[k];
    out << row("  vs published", difference);
  }
  if (!e.published.empty())
    out << "(\"vs published\": J1 in samples of " << e.dt * 1e3
        << " ms, J2-J9 relative in %; published: " << e.published_source << ")\n";
  return out.str();
}

nlohmann::json benchmark_json(const BenchmarkEvaluation& e) {
  nlohmann::json cases = nlohmann::json::array();
  for (const BenchmarkCaseCriteria& c : e.cases) {
    nlohmann::json j = nlohmann::json::array();
    for (std::size_t k = 0; k < 9; ++k)
      j.push_back(k == 0 ? c.criteria.j[0] * 1e3 : c.criteria.j[k]);
    cases.push_back({{"name", c.name}, {"J", j}});
  }
  return {{"units", "J1 ms, J2-J9 %"},
          {"published", e.published},
          {"published_case", e.published_case},
          {"published_source", e.published_source},
          {"cases", cases}};
}

}  // namespace rths::analysis
