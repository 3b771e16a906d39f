#pragma once
// The evaluation criteria of the RTHS benchmark problem (Silva, Gomez, Maghareh, Dyke & Spencer
// 2020, "Benchmark control problem for real-time hybrid simulation", Mech. Syst. Signal Process.
// 135, 106381), as its public evaluation script (F4_evaluation.m) computes them.
//
// Inputs: the command the integrator wanted at the experimental storey x_t (m), what the actuator
// realised there x_m (m), the RTHS floor displacements and those of the reference simulation
// (rows = steps at dt, columns = floors, m), and which storey is experimental.
// Outputs (all %, except J1):
//   tracking
//     J1 (s)  delay of x_m behind x_t at the cross-correlation peak (core::j1_delay), searched over
//             [-j1_max_lag, j1_max_lag]. The benchmark's own script searches 0..49 samples only
//             (12 ms at 4096 Hz), too short for a 26 ms actuator; callers state their range.
//     J2      100 std(x_m - x_t) / std(x_t)     (std removes the mean, as the script does)
//     J3      100 max|x_m - x_t| / max|x_t|     (core::j3_peak_tracking)
//   performance against the reference simulation
//     J4      100 std(x_m - d_ref) / std(d_ref),  d_ref the reference drift of the experimental
//             storey (the benchmark: floor 1, whose displacement is that drift)
//     J5      100 max|x_m - d_ref| / max|d_ref|
//     J6, J7  100 std(u_i - u_ref,i) / std(u_ref,i) for the first two other floors (benchmark:
//             floors 2 and 3)
//     J8, J9  100 max|u_i - u_ref,i| / max|u_ref,i| for the same floors
// A criterion without its floor (a one- or two-floor structure) is NaN: not applicable.
// Records of different length (a run that stopped early) are compared over the common part.

#include <array>
#include <span>
#include <string>

#include "core/structure.h"

namespace rths::core {

struct BenchmarkCriteria {
  std::array<double, 9> j{};  // j[0] = J1 (s), j[1..8] = J2..J9 (%)
  double j1_search = 0.0;     // s, the J1 lag range searched (+-)
  double J(int number) const { return j.at(static_cast<std::size_t>(number - 1)); }
};

// 100 std(compared - reference) / std(reference). Throws std::invalid_argument on empty or
// different-length inputs.
double normalised_std_error(std::span<const double> reference, std::span<const double> compared);

// @pre experimental_storey in [0, floors); response and reference have the same floors.
BenchmarkCriteria benchmark_criteria(std::span<const double> target,
                                     std::span<const double> measured, const Mat& response,
                                     const Mat& reference, int experimental_storey, double dt,
                                     double j1_max_lag);

// The name, unit and definition of each criterion, J1 first, as every report names them (text,
// JSON, Python, `rths run --help`). J1 is reported in ms, J2-J9 in %.
struct CriterionDefinition {
  const char* name;        // "J1"
  const char* unit;        // "ms" or "%"
  const char* definition;  // one line, in the terms above (x_t, x_m, d_ref, u_ref)
};
const std::array<CriterionDefinition, 9>& criterion_definitions();
// A criterion's value in its reported unit: J1 in ms, the others as computed (%).
double reported_value(const BenchmarkCriteria& criteria, int number);
// One line per criterion, "J1 (ms)  delay of ...", after a line naming x_t, x_m and d_ref.
std::string criteria_glossary();

// "J1 = 4.60 ms  J2 = 9.1 % ..." with n/a for NaN.
std::string format_criteria(const BenchmarkCriteria& criteria);

}  // namespace rths::core
