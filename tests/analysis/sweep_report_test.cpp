// The sweep's report: the paper's trends measured on hand-made rows (each claim on its own), and
// the two figures written where the report says.
#include "analysis/sweep/sweep_report.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include <unistd.h>

namespace rths::analysis {
namespace {

namespace fs = std::filesystem;

// `error_pct` is the row's E_rms; its paper's NRMSE is made to rise where E_rms falls (x period^2),
// so that a trend measured with the wrong one is seen.
SweepTableRow row(double period, double delay, double error_pct, double stiffness = 1e3,
                  const std::string& model = "linear") {
  SweepTableRow r;
  r.period = period;
  r.delay = delay;
  r.alpha = 0.5;
  r.stiffness = stiffness;
  r.dt = 0.002;
  r.motion = "record";
  r.model = model;
  r.rms_error_pct = error_pct;
  r.peak_error_pct = 1.5 * error_pct;
  r.nrmse_pct = error_pct * period * period * 100;
  r.eq2_paper = r.nrmse_pct / 1000;
  return r;
}

TEST(SweepTrends, FallingFractionCountsConsecutivePeriodPairsPerSeries) {
  // delay 4 ms falls over both pairs; delay 8 ms falls once and rises once: 3 of 4 pairs fall.
  const std::vector<SweepTableRow> rows = {
      row(0.5, 0.004, 10), row(1.0, 0.004, 5), row(2.0, 0.004, 1), row(2.0, 0.008, 3),
      row(0.5, 0.008, 20), row(1.0, 0.008, 2), row(1.0, 0.0, 0)};  // a zero delay is left out
  const SweepTrends trends = measure_trends(rows);
  EXPECT_DOUBLE_EQ(trends.period_falling_fraction, 0.75);
  EXPECT_EQ(trends.stiffness_max_relative_difference, 0.0);          // one stiffness
  EXPECT_TRUE(std::isnan(trends.nonlinear_to_linear_median_ratio));  // one model
  EXPECT_EQ(trends.diverged_points, 0u);
  // The paper's own NRMSE (kept for its Fig. 4) rises with period in these rows.
  EXPECT_LT(measure_trends(rows, SweepMeasure::kPaperNrmse).period_falling_fraction, 0.75);
  const nlohmann::json j = sweep_trends_json(rows);
  EXPECT_EQ(j["trends"]["measure"], "E_rms (%)");
  EXPECT_DOUBLE_EQ(j["trends"]["period_falling_pair_fraction"].get<double>(), 0.75);
  EXPECT_NE(j["paper_trends"]["measure"].get<std::string>().find("the paper's"), std::string::npos);
  EXPECT_TRUE(j["trends"]["nonlinear_to_linear_median_ratio"].is_null());
}

TEST(SweepTrends, StiffnessDifferenceIsRelativeToTheLargerError) {
  const std::vector<SweepTableRow> rows = {row(0.5, 0.004, 10, 1e3), row(0.5, 0.004, 8, 1e6),
                                           row(1.0, 0.004, 4, 1e3), row(1.0, 0.004, 4, 1e6)};
  EXPECT_DOUBLE_EQ(measure_trends(rows).stiffness_max_relative_difference, 0.2);
}

TEST(SweepTrends, NonlinearRatioIsTheMedianOverMatchingPointsAndDivergedPointsAreCounted) {
  std::vector<SweepTableRow> rows = {row(0.5, 0.004, 10),
                                     row(1.0, 0.004, 10),
                                     row(2.0, 0.004, 10),
                                     row(0.5, 0.004, 5, 1e3, "bilinear"),
                                     row(1.0, 0.004, 2, 1e3, "bilinear"),
                                     row(2.0, 0.004, 30, 1e3, "bilinear")};
  SweepTableRow diverged =
      row(3.0, 0.004, std::numeric_limits<double>::infinity(), 1e3, "bilinear");
  diverged.diverged = true;
  rows.push_back(diverged);
  const SweepTrends trends = measure_trends(rows);
  EXPECT_DOUBLE_EQ(trends.nonlinear_to_linear_median_ratio, 0.5);  // ratios 0.5, 0.2, 3
  EXPECT_EQ(trends.diverged_points, 1u);
}

TEST(SweepPlot, DelayFigureSitsBesideTheFigureNamed) {
  EXPECT_EQ(sweep_delay_plot_path("out/sweep.png"), fs::path("out/sweep_vs_delay.png"));
}

TEST(SweepPlot, WritesBothFiguresAsPngAndSvg) {
  const fs::path dir =
      fs::temp_directory_path() / ("rths_sweep_report_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::vector<SweepTableRow> rows = {row(0.5, 0.004, 10), row(1.0, 0.004, 5),
                                           row(0.5, 0.008, 20), row(1.0, 0.008, 9)};
  const fs::path png = dir / "sweep.png";
  write_sweep_plot(rows, png, "report test",
                   [](double period, double, double) { return period * 0.016; });
  for (const fs::path& file : {png, sweep_delay_plot_path(png)}) {
    EXPECT_GT(fs::file_size(file), 1000u) << file;
    fs::path svg = file;
    EXPECT_GT(fs::file_size(svg.replace_extension(".svg")), 1000u) << svg;
  }
  // The error-against-period figure's curves say what their number is (one curve per delay).
  std::ifstream in(dir / "sweep.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(svg.find("delay 4 ms"), std::string::npos);
  EXPECT_NE(svg.find("delay 8 ms"), std::string::npos);
  EXPECT_EQ(svg.find("0.000010"), std::string::npos) << "log ticks as %g";
  EXPECT_THROW(write_sweep_plot({}, png, "empty"), std::invalid_argument);
  EXPECT_THROW(write_sweep_plot({row(0.5, 0.0, 0)}, png, "no delay"), std::invalid_argument);
  fs::remove_all(dir);
}

TEST(SweepPlot, ModelNamesReadAsWordsWithUnits) {
  EXPECT_EQ(model_label("linear"), "linear");
  EXPECT_EQ(model_label("bilinear:uy=0.005:b=0.1"), "bilinear (uy = 5 mm, b = 0.1)");
}

// Every curve's diverged points are their own legend entry in the curve's colour, so that no
// diverged point of one delay or model hides another's; each model is named on both figures.
TEST(SweepPlot, EveryDivergedPointIsSeenWithItsDelayAndModel) {
  const fs::path dir =
      fs::temp_directory_path() / ("rths_sweep_diverged_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<SweepTableRow> rows;
  for (const std::string model : {"linear", "bilinear:uy=0.005:b=0.1"}) {
    for (double delay : {0.004, 0.030}) {
      for (double period : {0.2, 0.5, 1.0}) {
        SweepTableRow r = row(period, delay, 10 * delay / period, 1e3, model);
        r.diverged = delay > 0.02 && period < 0.6;
        rows.push_back(r);
      }
    }
  }
  const fs::path png = dir / "sweep.png";
  write_sweep_plot(rows, png, "diverged test");
  std::ifstream in(dir / "sweep.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* entry :
       {"diverged: above the curves, in its curve's colour", "delay 30 ms, linear",
        "delay 4 ms, linear", "delay 4 ms, bilinear (uy = 5 mm, b = 0.1)", "period T (s)",
        "E_rms (%, log)", "NRMSE (%, log)", "the paper's Fig. 4"}) {
    EXPECT_NE(svg.find(entry), std::string::npos) << entry;
  }
  // E_rms leads: its panel is drawn first, the paper's after it.
  EXPECT_LT(svg.find("E_rms (%, log)"), svg.find("NRMSE (%, log)"));
  // One legend entry for every curve's diverged points, on each of the three panels.
  std::size_t entries = 0;
  for (auto at = svg.find(">diverged: above the curves"); at != std::string::npos;
       at = svg.find(">diverged: above the curves", at + 1))
    ++entries;
  EXPECT_EQ(entries, 3u);
  EXPECT_EQ(svg.find(": diverged<"), std::string::npos);
  std::ifstream by_delay_in(dir / "sweep_vs_delay.svg");
  const std::string by_delay((std::istreambuf_iterator<char>(by_delay_in)),
                             std::istreambuf_iterator<char>());
  for (const char* entry : {"T = 0.2 s, linear", "T = 0.2 s, bilinear (uy = 5 mm, b = 0.1)",
                            "delay (ms)", "E_rms (%, log)"}) {
    EXPECT_NE(by_delay.find(entry), std::string::npos) << entry;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rths::analysis
