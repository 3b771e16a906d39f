#include "analysis/results_csv.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "analysis/atomic_file.h"

namespace rths::analysis {
namespace {

std::string safe_name(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_';
  return out.empty() ? "run" : out;
}

}  // namespace

std::vector<std::string> result_column_names(const std::string& run_name, const core::SimulationResult& result) {
  const std::string prefix = safe_name(run_name) + ".";
  std::vector<std::string> names;
  for (Eigen::Index i = 0; i < result.displacement.cols(); ++i) {
    names.push_back(prefix + "u_floor" + std::to_string(i + 1) + "_m");
  }
  for (Eigen::Index j = 0; j < result.command.cols(); ++j) {
    const std::string act = "_act" + std::to_string(j + 1);
    names.push_back(prefix + "command" + act + "_m");
    names.push_back(prefix + "measured" + act + "_m");
    names.push_back(prefix + "force" + act + "_N");
  }
  return names;
}

void write_results_csv(const std::filesystem::path& csv, const std::vector<NamedResult>& runs) {
  if (runs.empty()) throw std::invalid_argument("results CSV: no runs to write");
  const double dt = runs.front().result->dt;
  std::size_t rows = 0;
  for (const NamedResult& run : runs) {
    if (std::abs(run.result->dt - dt) > 1e-12 * dt) {
      throw std::invalid_argument("results CSV: run '" + run.name + "' has a different dt");
    }
    rows = std::max(rows, run.result->steps());
  }
  AtomicFile file(csv);
  std::ofstream& out = file.stream();
  out.precision(10);
  out << "step,time_s";
  for (const NamedResult& run : runs) {
    for (const std::string& name : result_column_names(run.name, *run.result)) out << "," << name;
  }
  out << "\n";
  for (std::size_t k = 0; k < rows; ++k) {
    out << k << "," << static_cast<double>(k) * dt;
    for (const NamedResult& run : runs) {
      const core::SimulationResult& r = *run.result;
      const auto row = static_cast<Eigen::Index>(k);
      const bool has = k < r.steps();
      for (Eigen::Index i = 0; i < r.displacement.cols(); ++i) {
        out << ",";
        if (has) out << r.displacement(row, i);
      }
      for (Eigen::Index j = 0; j < r.command.cols(); ++j) {
        if (has) {
          out << "," << r.command(row, j) << "," << r.realised(row, j) << "," << r.measured_force(row, j);
        } else {
          out << ",,,";
        }
      }
    }
    out << "\n";
  }
  file.commit();
}

}  // namespace rths::analysis
