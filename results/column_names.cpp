#include "results/column_names.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace rths::results {
namespace {

std::string safe_name(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_';
  return out.empty() ? "run" : out;
}

}  // namespace

std::string result_column_prefix(const std::string& run_name) { return safe_name(run_name) + "_"; }

namespace {

// "<quantity><index>_<unit>", appended piece by piece: GCC 12 misreads `"text" +
// std::to_string(...)` (-Wrestrict).
std::string indexed(const char* quantity, std::size_t index, const char* unit) {
  std::string name = quantity;
  name += std::to_string(index);
  name += '_';
  name += unit;
  return name;
}

}  // namespace

std::string displacement_column(std::size_t floor) { return indexed("u_floor", floor, "m"); }
std::string velocity_column(std::size_t floor) { return indexed("v_floor", floor, "m_per_s"); }
std::string acceleration_column(std::size_t floor) { return indexed("a_floor", floor, "m_per_s2"); }
std::string command_column(std::size_t actuator) { return indexed("command_act", actuator, "m"); }
std::string measured_column(std::size_t actuator) { return indexed("measured_act", actuator, "m"); }
std::string force_column(std::size_t actuator) { return indexed("force_act", actuator, "N"); }

std::string drift_column(std::size_t upper, std::size_t lower) {
  std::string name = indexed("drift_floor", upper, "");  // "drift_floor<i>_"
  name += lower == 0 ? std::string("ground_m") : indexed("floor", lower, "m");
  return name;
}

std::vector<std::string> result_column_names(const std::string& run_name,
                                             const core::SimulationResult& result) {
  const std::string prefix = result_column_prefix(run_name);
  std::vector<std::string> names;
  for (Eigen::Index i = 0; i < result.displacement.cols(); ++i)
    names.push_back(prefix + displacement_column(static_cast<std::size_t>(i + 1)));
  for (Eigen::Index j = 0; j < result.command.cols(); ++j) {
    const auto actuator = static_cast<std::size_t>(j + 1);
    names.push_back(prefix + command_column(actuator));
    names.push_back(prefix + measured_column(actuator));
    names.push_back(prefix + force_column(actuator));
  }
  return names;
}

}  // namespace rths::results
