#include "analysis/results_csv.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace rths::analysis {
namespace {

std::string safe_name(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_';
  return out.empty() ? "run" : out;
}

}  // namespace

std::string result_column_prefix(const std::string& run_name) { return safe_name(run_name) + "_"; }

std::vector<std::string> result_column_names(const std::string& run_name,
                                             const core::SimulationResult& result) {
  const std::string prefix = result_column_prefix(run_name);
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

}  // namespace rths::analysis
