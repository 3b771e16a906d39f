#pragma once
// A study judged by the RTHS benchmark problem's criteria (study.benchmark, Silva et al. 2020):
// every case but the reference, J1-J9 (core::benchmark_criteria) with
//   y_n  the command the integrator sent to the experimental DOF (SimulationResult::command),
//   x_m  the displacement the actuator measured there (SimulationResult::realised),
//   the numerical response (every DOF) against the exact linear response of the whole structure
//   (core::exact_linear_response of M, C, K before the split, same motion and dt).
// J1 is searched over +-j1_search (default 49 samples, as F4_evaluation.m searches 0..49).
// Published values (benchmark.published, for benchmark.published_case) are compared with only
// for that case, and only when the run's motion and structure are those they were computed on,
// by content: motion_key and structure_key against benchmark.published_motion_sha256 and
// published_structure_sha256. A compensated case, or a run on another motion or structure, has
// no published value (no published row is printed), which the reports say, naming the keys.
// Every criterion is named with its unit and definition (core::criterion_definitions).

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/study_run/study_run.h"
#include "core/benchmark_criteria.h"

namespace rths::analysis {

struct BenchmarkCaseCriteria {
  std::string name;
  core::BenchmarkCriteria criteria;
};

struct BenchmarkEvaluation {
  std::vector<BenchmarkCaseCriteria> cases;
  std::vector<double> published;  // J1 (ms), J2-J9 (%); empty when none
  std::string published_case, published_source;
  // The run's motion and structure keys are the published ones (false without them).
  bool published_motion_matches = false;
  std::string run_motion_key, run_structure_key;  // this run's (empty without published values)
  // Why the published values are compared with nowhere (empty when they are for published_case).
  std::string published_note;
  double dt = 0.0;           // s
  double j1_search = 0.0;    // s, J1's lag range (+-)
  int experimental_dof = 0;  // 0-based
  // The exact response of the whole structure every case is judged against (m, relative to
  // the ground; a row per step of dt, a column per floor).
  core::Mat reference_displacement;
  // Whether case i's criteria have published values to be compared with.
  bool compared_with_published(const BenchmarkCaseCriteria& c) const;
};

// SHA-256 of a structure (n, M, K, iota): with study::motion_key (study/motion_key.h), what
// published values are keyed by.
std::string structure_key(const core::StructuralModel& model);

// 100 (J - J_published) / J_published for J2-J9 (%), J1 - J1_published (ms) for J1.
std::array<double, 9> against_published(const BenchmarkEvaluation& e,
                                        const BenchmarkCaseCriteria& c);

// Empty when the study has no `benchmark` section. Throws std::invalid_argument naming
// benchmark.experimental_dof or benchmark.published when they do not fit the structure.
std::optional<BenchmarkEvaluation> evaluate_benchmark(const study::PreparedStudy& prepared,
                                                      const StudyOutcome& outcome);

// Aligned columns, one unit each (J1 (ms), J2-J9 (%)): the published row, each case; then, where
// a case is compared with published values, a second table of its differences (J1 in ms, J2-J9
// relative, %); then what has no published value and why; then every criterion's definition.
std::string benchmark_table(const BenchmarkEvaluation& evaluation);
// {"criteria": [{name, unit, definition}], "j1_search_ms", "published": {case, source,
//  motion_matches, note, criteria: [{name, value, unit, definition}]} or null,
//  "cases": [{name, criteria: [{name, value, unit, definition}], vs_published: [{name, value, unit,
//  definition}] or null}]}. A NaN criterion (no such floor) is null.
nlohmann::json benchmark_json(const BenchmarkEvaluation& evaluation);

}  // namespace rths::analysis
