#include "analysis/benchmark/benchmark_perturbation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "study/study.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kCase1 =
    std::filesystem::path(RTHS_SOURCE_DIR) / "configs/benchmark/case_1.textproto";

TEST(BenchmarkPerturbation, DrawsAreSeededAndSpreadAsTheBenchmarkDrawsThem) {
  const auto a = draw_benchmark_plants(3, 9, 1.19e6), b = draw_benchmark_plants(3, 9, 1.19e6);
  const auto other = draw_benchmark_plants(3, 10, 1.19e6);
  ASSERT_EQ(a.size(), 3u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].beta1, b[i].beta1);
    EXPECT_EQ(a[i].stiffness, b[i].stiffness);
    EXPECT_NE(a[i].beta2, other[i].beta2);
  }
  constexpr int kDraws = 4000;
  const auto many = draw_benchmark_plants(kDraws, 1, 1.19e6);
  const auto check = [&](double PlantDraw::*field, double mean, double sd) {
    double sum = 0.0, square = 0.0;
    for (const PlantDraw& d : many) sum += d.*field;
    const double m = sum / kDraws;
    for (const PlantDraw& d : many) square += (d.*field - m) * (d.*field - m);
    EXPECT_NEAR(m, mean, 4 * sd / std::sqrt(kDraws));
    EXPECT_NEAR(std::sqrt(square / (kDraws - 1)), sd, 0.06 * sd);
  };
  check(&PlantDraw::beta1, 425.0, 3.3);
  check(&PlantDraw::beta2, 9.9976e4, 3.3e3);
  check(&PlantDraw::a3, 3.3, 1.3);
  check(&PlantDraw::stiffness, 1.19e6, 5e4);
}

TEST(BenchmarkPerturbation, ADrawReachesThePlantAndTheSpecimenButNotTheReference) {
  const config::Study study = study::load_study(kCase1);
  EXPECT_EQ(experimental_stiffness(study), 1.19e6);
  const PlantDraw draw{430.0, 1.02e5, 2.5, 1.21e6};
  const config::Study perturbed = perturbed_study(study, draw);
  EXPECT_EQ(perturbed.substructuring().experimental_dofs(0).stiffness(), 1.21e6);
  EXPECT_EQ(perturbed.structure().DebugString(), study.structure().DebugString());
  int plants = 0;
  for (const config::Case& c : perturbed.cases())
    for (const config::DelayStage& stage : c.delay()) {
      if (!stage.has_tracking_loop()) continue;
      const auto& plant = stage.tracking_loop().benchmark_plant();
      EXPECT_EQ(plant.beta1(), 430.0);
      EXPECT_EQ(plant.beta2(), 1.02e5);
      EXPECT_EQ(plant.a3(), 2.5);
      EXPECT_EQ(plant.stiffness(), 1.21e6);
      ++plants;
    }
  EXPECT_EQ(plants, 1);
  config::Study no_benchmark = study;
  no_benchmark.clear_benchmark();
  EXPECT_THROW(perturbed_study(no_benchmark, draw), std::invalid_argument);
  config::Study elsewhere = study;
  elsewhere.mutable_benchmark()->set_experimental_dof(2);
  EXPECT_THROW(experimental_stiffness(elsewhere), std::invalid_argument);
}

TEST(BenchmarkPerturbation, SpreadIsMeanAndSampleStdWithJ1InMilliseconds) {
  BenchmarkEvaluation first, second;
  first.cases.push_back({"pi", {}});
  second.cases.push_back({"pi", {}});
  first.cases[0].criteria.j = {0.004, 10, 11, 30, 20, 30, 30, 15, 15};
  second.cases[0].criteria.j = {0.005, 12, 11, 34, 20, 30, 30, 15, 15};
  const auto spread = criteria_spread({first, second});
  ASSERT_EQ(spread.size(), 1u);
  EXPECT_EQ(spread[0].draws, 2);
  EXPECT_NEAR(spread[0].mean[0], 4.5, 1e-12);
  EXPECT_NEAR(spread[0].std[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(spread[0].mean[1], 11.0, 1e-12);
  EXPECT_NEAR(spread[0].std[3], std::sqrt(8.0), 1e-12);
  EXPECT_EQ(spread[0].std[2], 0.0);
  EXPECT_NE(spread_table(spread, 4).find("pi: 2 draws (seed 4)"), std::string::npos);
  EXPECT_EQ(spread_json(spread, 4)["cases"][0]["criteria"][1]["mean"], 11.0);
  EXPECT_EQ(spread_json(spread, 4)["cases"][0]["criteria"][1]["name"], "J2");
  EXPECT_EQ(spread_json(spread, 4)["cases"][0]["criteria"][0]["unit"], "ms");
}

}  // namespace
}  // namespace rths::analysis
