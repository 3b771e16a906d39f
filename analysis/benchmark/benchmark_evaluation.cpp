#include "analysis/benchmark/benchmark_evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/structure_response.h"
#include "study/motion_key.h"
#include "util/sha256.h"
#include "util/text_table.h"

namespace rths::analysis {
namespace {

std::vector<double> column(const core::Mat& m, Eigen::Index c) {
  std::vector<double> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) out[static_cast<std::size_t>(i)] = m(i, c);
  return out;
}

// A table's cell: the value to `decimals` decimals, or n/a where a criterion has none (NaN).
std::string cell(double value, int decimals = 2) {
  return std::isnan(value) ? "n/a" : fmt::format("{:.{}f}", value, decimals);
}

// A difference's cell: signed, two decimals, n/a for NaN.
std::string signed_cell(double value) {
  return std::isnan(value) ? "n/a" : fmt::format("{:+.2f}", value);
}

nlohmann::json number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

// [{name, value, unit, definition}] of nine values in the criteria's reported units, or with
// `unit` and `definition` given for every one (differences).
nlohmann::json named(const std::array<double, 9>& values, const char* unit = nullptr,
                     const char* definition = nullptr) {
  nlohmann::json out = nlohmann::json::array();
  const auto& definitions = core::criterion_definitions();
  for (std::size_t k = 0; k < 9; ++k) {
    const core::CriterionDefinition& d = definitions[k];
    out.push_back({{"name", d.name},
                   {"value", number(values[k])},
                   {"unit", unit ? unit : d.unit},
                   {"definition", definition ? definition : d.definition}});
  }
  return out;
}

std::array<double, 9> reported(const core::BenchmarkCriteria& c) {
  std::array<double, 9> out{};
  for (int j = 1; j <= 9; ++j) out[static_cast<std::size_t>(j - 1)] = core::reported_value(c, j);
  return out;
}

}  // namespace

bool BenchmarkEvaluation::compared_with_published(const BenchmarkCaseCriteria& c) const {
  return !published.empty() && published_motion_matches && c.name == published_case;
}

std::array<double, 9> against_published(const BenchmarkEvaluation& e,
                                        const BenchmarkCaseCriteria& c) {
  std::array<double, 9> out{};
  const std::array<double, 9> j = reported(c.criteria);
  out[0] = j[0] - e.published.at(0);
  for (std::size_t k = 1; k < 9; ++k) out[k] = 100.0 * (j[k] - e.published.at(k)) / e.published[k];
  return out;
}

namespace {

// Whether the run's motion and structure are those the published values were computed on, by
// their keys (motion_key, structure_key); why not, naming this run's keys, when they are not.
void judge_published_key(const config::BenchmarkEvaluation& spec, const config::Study& study,
                         const std::filesystem::path& base_dir, const core::StructuralModel& whole,
                         BenchmarkEvaluation& out) {
  out.run_motion_key = study::motion_key(study::load_motion(study.motion(), base_dir));
  out.run_structure_key = structure_key(whole);
  const std::string keys = "this run's motion sha256 " + out.run_motion_key +
                           ", structure sha256 " + out.run_structure_key;
  if (spec.published_motion_sha256().empty() || spec.published_structure_sha256().empty()) {
    out.published_note =
        "benchmark.published_motion_sha256 and published_structure_sha256 are not both set: what "
        "the published values were computed on is unknown, so no case is compared with them (" +
        keys + ")";
    return;
  }
  out.published_motion_matches = out.run_motion_key == spec.published_motion_sha256();
  const bool structure = out.run_structure_key == spec.published_structure_sha256();
  if (!out.published_motion_matches || !structure) {
    const std::string what =
        !out.published_motion_matches
            ? "motion (" + study.motion().path() + ")" +
                  (structure ? " is not the one" : " and structure are not the ones")
            : std::string("structure is not the one");
    out.published_note = "this run's " + what + " the published values were computed on (" + keys +
                         "; published: motion " + spec.published_motion_sha256() + ", structure " +
                         spec.published_structure_sha256() +
                         "): the published values have none for it";
    out.published_motion_matches = false;
  }
}

}  // namespace

std::string structure_key(const core::StructuralModel& model) {
  std::vector<double> values{static_cast<double>(model.dofs())};
  for (const core::Mat* m : {&model.mass, &model.stiffness})
    values.insert(values.end(), m->data(), m->data() + m->size());
  values.insert(values.end(), model.influence.data(),
                model.influence.data() + model.influence.size());
  return util::bytes_sha256(values.data(), values.size() * sizeof(double));
}

std::optional<BenchmarkEvaluation> evaluate_benchmark(const study::PreparedStudy& prepared,
                                                      const StudyOutcome& outcome) {
  const config::Study& study = prepared.config;
  if (!study.has_benchmark()) return std::nullopt;
  const config::BenchmarkEvaluation& spec = study.benchmark();
  const core::StructuralModel whole = study::make_structure(study.structure(), prepared.base_dir);
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
  if (!out.published.empty()) judge_published_key(spec, study, prepared.base_dir, whole, out);
  const core::LinearResponse reference = core::exact_linear_response(whole, prepared.motion);
  out.j1_search = spec.j1_search() > 0 ? spec.j1_search() : 49 * out.dt;
  out.experimental_dof = dof;
  out.reference_displacement = reference.displacement;
  // The study's reference case is not judged (in a distributed outcome, where every case is a
  // recorded one, by its name).
  const std::string reference_name =
      outcome.lag_free_reference
          ? (study.cases_size() > 0 ? study::reference_case(study).name() : std::string())
          : outcome.cases.at(outcome.reference_index).name;
  for (const CaseOutcome& c : outcome.cases) {
    if (c.name == reference_name || c.simulation.command.cols() == 0) continue;
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
                                          reference.displacement, dof, out.dt, out.j1_search)});
  }
  return out;
}

std::string benchmark_table(const BenchmarkEvaluation& e) {
  std::ostringstream out;
  out << "RTHS benchmark criteria against the exact response of the whole structure (J1 searched "
         "over +-"
      << cell(e.j1_search * 1e3) << " ms)\n";
  using Align = util::TextTable::Align;
  const auto& definitions = core::criterion_definitions();
  std::vector<util::TextTable::Column> columns = {{"case", Align::kLeft, 40}};
  for (const core::CriterionDefinition& d : definitions)
    columns.push_back({std::string(d.name) + " (" + d.unit + ")", Align::kRight});
  util::TextTable values(columns);
  const auto add = [&](const std::string& name, const std::array<double, 9>& j,
                       const auto& format) {
    std::vector<std::string> row = {name};
    for (double v : j) row.push_back(format(v));
    values.add_row(std::move(row));
  };
  const auto plain = [](double v) { return cell(v); };
  std::array<double, 9> published{};
  if (!e.published.empty() && e.published_motion_matches) {
    std::copy(e.published.begin(), e.published.end(), published.begin());
    add("published (" + e.published_case + ")", published, plain);
  }
  for (const BenchmarkCaseCriteria& c : e.cases) add(c.name, reported(c.criteria), plain);
  out << values.render();

  std::vector<util::TextTable::Column> difference_columns = {{"case", Align::kLeft, 40},
                                                             {"J1 diff (ms)", Align::kRight}};
  for (std::size_t k = 1; k < 9; ++k)
    difference_columns.push_back({std::string(definitions[k].name) + " rel (%)", Align::kRight});
  util::TextTable differences(difference_columns);
  bool any = false;
  for (const BenchmarkCaseCriteria& c : e.cases) {
    if (!e.compared_with_published(c)) continue;
    std::vector<std::string> row = {c.name};
    for (double v : against_published(e, c)) row.push_back(signed_cell(v));
    differences.add_row(std::move(row));
    any = true;
  }
  if (any)
    out << "against the published values (" << e.published_source
        << "): J1 - J1_published in ms, 100 (J - J_published) / J_published in % for J2-J9\n"
        << differences.render();
  if (!e.published.empty()) {
    if (!e.published_note.empty()) {
      out << "no published value: " << e.published_note << "\n";
    } else {
      std::string others;
      for (const BenchmarkCaseCriteria& c : e.cases)
        if (!e.compared_with_published(c)) others += (others.empty() ? "" : ", ") + c.name;
      if (!others.empty())
        out << "no published value for " << others << " (the published values are "
            << e.published_case << "'s)\n";
    }
  }
  out << core::criteria_glossary();
  return out.str();
}

nlohmann::json benchmark_json(const BenchmarkEvaluation& e) {
  nlohmann::json criteria = nlohmann::json::array();
  for (const core::CriterionDefinition& d : core::criterion_definitions())
    criteria.push_back({{"name", d.name}, {"unit", d.unit}, {"definition", d.definition}});
  nlohmann::json cases = nlohmann::json::array();
  for (const BenchmarkCaseCriteria& c : e.cases) {
    nlohmann::json vs = nullptr;
    if (e.compared_with_published(c)) {
      vs = named(against_published(e, c), "%",
                 "100 (J - J_published) / J_published; for J1, J1 - J1_published in ms");
      vs[0]["unit"] = "ms";
      vs[0]["definition"] = "J1 - J1_published (ms)";
    }
    cases.push_back(
        {{"name", c.name}, {"criteria", named(reported(c.criteria))}, {"vs_published", vs}});
  }
  nlohmann::json published = nullptr;
  if (!e.published.empty()) {
    std::array<double, 9> values{};
    std::copy(e.published.begin(), e.published.end(), values.begin());
    published = {
        {"case", e.published_case},
        {"source", e.published_source},
        {"motion_matches", e.published_motion_matches},
        {"note", e.published_note.empty() ? nlohmann::json() : nlohmann::json(e.published_note)},
        {"criteria", named(values)}};
  }
  return {{"criteria", criteria},
          {"j1_search_ms", e.j1_search * 1e3},
          {"published", published},
          {"cases", cases}};
}

}  // namespace rths::analysis
