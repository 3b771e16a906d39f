#include "analysis/benchmark/benchmark_perturbation.h"

#include <fmt/format.h>

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "util/text_table.h"

namespace rths::analysis {
namespace {

// Nominal values and standard deviations of F1_input_file.m (Table 2 of the paper).
constexpr double kBeta1 = 425.0, kBeta1Sd = 3.3;
constexpr double kBeta2 = 9.9976e4, kBeta2Sd = 3.3e3;  // 1/s
constexpr double kA3 = 3.3, kA3Sd = 1.3;               // 1/s
constexpr double kStiffnessSd = 5e4;                   // N/m

int experimental_dof(const config::Study& study) {
  if (!study.has_benchmark())
    throw std::invalid_argument("perturbed plants need the study's benchmark section");
  return study.benchmark().experimental_dof() == 0 ? 1 : study.benchmark().experimental_dof();
}

config::ExperimentalDof* find_dof(config::Study& study, int dof) {
  for (config::ExperimentalDof& spec : *study.mutable_substructuring()->mutable_experimental_dofs())
    if (spec.dof() == dof) return &spec;
  throw std::invalid_argument("benchmark.experimental_dof: DOF " + std::to_string(dof) +
                              " is not in substructuring.experimental_dofs");
}

void set_plant(config::DelayStage::BenchmarkPlant* plant, const PlantDraw& draw) {
  plant->set_beta1(draw.beta1);
  plant->set_beta2(draw.beta2);
  plant->set_a3(draw.a3);
  plant->set_stiffness(draw.stiffness);
  plant->set_damping(0.0);  // from zeta_e and the drawn stiffness
}

}  // namespace

std::vector<PlantDraw> draw_benchmark_plants(int count, std::uint64_t seed,
                                             double nominal_stiffness) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<PlantDraw> draws;
  for (int i = 0; i < count; ++i) {
    PlantDraw d;
    d.beta1 = kBeta1 + kBeta1Sd * normal(rng);
    d.beta2 = kBeta2 + kBeta2Sd * normal(rng);
    d.a3 = kA3 + kA3Sd * normal(rng);
    d.stiffness = nominal_stiffness + kStiffnessSd * normal(rng);
    draws.push_back(d);
  }
  return draws;
}

double experimental_stiffness(const config::Study& study) {
  config::Study copy = study;
  return find_dof(copy, experimental_dof(study))->stiffness();
}

config::Study perturbed_study(const config::Study& study, const PlantDraw& draw) {
  config::Study out = study;
  find_dof(out, experimental_dof(study))->set_stiffness(draw.stiffness);
  for (config::Case& c : *out.mutable_cases()) {
    for (config::DelayStage& stage : *c.mutable_delay()) {
      if (!stage.has_tracking_loop() || !stage.tracking_loop().has_benchmark_plant()) continue;
      set_plant(stage.mutable_tracking_loop()->mutable_benchmark_plant(), draw);
    }
  }
  return out;
}

std::vector<CriteriaSpread> criteria_spread(const std::vector<BenchmarkEvaluation>& draws) {
  std::vector<CriteriaSpread> out;
  if (draws.empty()) return out;
  for (std::size_t c = 0; c < draws.front().cases.size(); ++c) {
    CriteriaSpread s;
    s.name = draws.front().cases[c].name;
    s.draws = static_cast<int>(draws.size());
    for (std::size_t j = 0; j < 9; ++j) {
      const double scale = j == 0 ? 1e3 : 1.0;  // J1 in ms
      double sum = 0.0, square = 0.0;
      for (const BenchmarkEvaluation& e : draws) sum += scale * e.cases.at(c).criteria.j[j];
      s.mean[j] = sum / s.draws;
      for (const BenchmarkEvaluation& e : draws)
        square += std::pow(scale * e.cases.at(c).criteria.j[j] - s.mean[j], 2);
      s.std[j] = s.draws > 1 ? std::sqrt(square / (s.draws - 1)) : 0.0;
    }
    out.push_back(s);
  }
  return out;
}

std::string spread_table(const std::vector<CriteriaSpread>& spread, std::uint64_t seed) {
  std::ostringstream out;
  using Align = util::TextTable::Align;
  const auto& definitions = core::criterion_definitions();
  for (const CriteriaSpread& s : spread) {
    out << "perturbed plants, " << s.name << ": " << s.draws << " draws (seed " << seed
        << "), mean +- std\n";
    util::TextTable table({{"criterion", Align::kLeft},
                           {"mean", Align::kRight},
                           {"std", Align::kRight},
                           {"unit", Align::kLeft}});
    for (std::size_t j = 0; j < 9; ++j) {
      table.add_row({definitions[j].name, fmt::format("{:.2f}", s.mean[j]),
                     fmt::format("{:.2f}", s.std[j]), definitions[j].unit});
    }
    out << table.render();
  }
  return out.str();
}

nlohmann::json spread_json(const std::vector<CriteriaSpread>& spread, std::uint64_t seed) {
  nlohmann::json cases = nlohmann::json::array();
  const auto& definitions = core::criterion_definitions();
  for (const CriteriaSpread& s : spread) {
    nlohmann::json criteria = nlohmann::json::array();
    for (std::size_t j = 0; j < 9; ++j)
      criteria.push_back({{"name", definitions[j].name},
                          {"mean", s.mean[j]},
                          {"std", s.std[j]},
                          {"unit", definitions[j].unit},
                          {"definition", definitions[j].definition}});
    cases.push_back({{"name", s.name}, {"draws", s.draws}, {"criteria", criteria}});
  }
  return {{"seed", seed}, {"cases", cases}};
}

}  // namespace rths::analysis
