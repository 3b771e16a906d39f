// The figures of a study of many floors and actuators (analysis/study_run/response_envelope_plots.h): the
// envelope's numbers against the histories they come from, the floors chosen, and a 14-storey
// building with an actuator in every storey drawn as pages that fit a page, every actuator on one.
#include "analysis/study_run/response_envelope_plots.h"

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "analysis/common/compare.h"
#include "study/study.h"
#include "tests/support/log_stamps.h"
#include "tests/support/png_size.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kConfigs = RTHS_SOURCE_DIR "/configs";
constexpr int kStoreys = 14;

// A 14-storey shear building, half of every storey experimental (14 actuators), 2 s of El Centro.
study::PreparedStudy tall_building() {
  std::ostringstream masses, stiffnesses;
  for (int i = 0; i < kStoreys; ++i) {
    masses << (i ? ", " : "") << 2.0e5;
    stiffnesses << (i ? ", " : "") << 1.5e8 - 5.0e6 * i;
  }
  const std::string text =
      "name: \"tall\" structure { shear_building { storey_mass: [" + masses.str() +
      "] storey_stiffness: [" + stiffnesses.str() +
      "] } damping { rayleigh { zeta: 0.05 mode_i: 1 mode_j: 2 } } } "
      "motion { path: \"../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: 2 } "
      "integrator { dt: 0.001 } substructuring { experimental_fraction: 0.5 } "
      "cases { name: \"reference\" } cases { name: \"lag_2ms\" delay { shift { delay: 0.002 } } }";
  return study::prepare_study(study::parse_study(text, "test"), kConfigs);
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

double peak_abs_difference(const std::vector<double>& upper, const std::vector<double>& lower) {
  double peak = 0.0;
  for (std::size_t k = 0; k < upper.size(); ++k)
    peak = std::max(peak, std::abs(upper[k] - (lower.empty() ? 0.0 : lower[k])));
  return peak;
}

// Every figure a study may have left in a folder, its actuator pages among them by page number:
// what a run without plots removes (analysis/distributed) and what `rths sites` lists.
TEST(ResponseEnvelopePlots, TheStudyPlotFilesOfAFolderNameItsActuatorPages) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_study_plot_files_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (const char* name : {"actuators_10.png", "actuators_2.svg", "actuators_2.png",
                           "actuators_x.png", "actuators_3.pdf", "results.csv"})
    std::ofstream(dir / name) << "x";
  std::vector<std::string> expected = study_plot_files();
  for (const char* name : {"actuators_2.png", "actuators_2.svg", "actuators_10.png"})
    expected.push_back(name);
  EXPECT_EQ(study_plot_files(dir), expected);
  remove_many_dof_figures(dir);
  EXPECT_EQ(study_plot_files(dir), study_plot_files());
  EXPECT_TRUE(std::filesystem::exists(dir / "actuators_x.png"));
  std::filesystem::remove_all(dir);
}

TEST(ResponseEnvelopePlots, ChosenFloorsAreEvenlySpacedFromTheFirstToTheTop) {
  std::vector<int> every(kStoreys);
  for (int i = 0; i < kStoreys; ++i) every[static_cast<std::size_t>(i)] = i;
  const std::vector<int> chosen = chosen_floors(every);
  EXPECT_EQ(chosen, (std::vector<int>{0, 3, 5, 8, 10, 13}));
  EXPECT_EQ(chosen_floors({0, 249, 499, 749, 999}), (std::vector<int>{0, 249, 499, 749, 999}));
}

// The drift between recorded floors i < j is max |u_j - u_i| / (j - i); with every floor recorded
// it is the inter-storey drift, the first storey's against the ground.
TEST(ResponseEnvelopePlots, PeaksAndDriftsOverHeightAreTheHistoriesPeaks) {
  const StudyOutcome outcome = run_study(tall_building());
  const CaseOutcome& lagged = outcome.cases[1];
  ASSERT_EQ(lagged.status, "completed") << lagged.status_detail;
  std::vector<std::vector<double>> u;
  for (int dof = 0; dof < kStoreys; ++dof) u.push_back(floor_history(lagged.simulation, dof));

  const util::Series peak =
      peak_over_height(lagged, recorded_floors(lagged.simulation), false, "lag_2ms", "lines");
  ASSERT_EQ(peak.y.size(), static_cast<std::size_t>(kStoreys + 1));
  EXPECT_EQ(peak.x.front(), 0.0);  // the ground
  for (int dof = 0; dof < kStoreys; ++dof) {
    EXPECT_EQ(peak.y[static_cast<std::size_t>(dof + 1)], dof + 1.0);
    EXPECT_DOUBLE_EQ(peak.x[static_cast<std::size_t>(dof + 1)],
                     peak_abs_difference(u[static_cast<std::size_t>(dof)], {}) * 1e3);
  }
  const util::Series drift =
      peak_over_height(lagged, recorded_floors(lagged.simulation), true, "", "lines");
  ASSERT_EQ(drift.x.size(), static_cast<std::size_t>(kStoreys));
  EXPECT_DOUBLE_EQ(drift.x[0], peak_abs_difference(u[0], {}) * 1e3);
  EXPECT_DOUBLE_EQ(drift.x[5], peak_abs_difference(u[5], u[4]) * 1e3);
  EXPECT_GT(drift.x[5], 0.0);

  const util::Series sparse = peak_over_height(lagged, {0, 4, 13}, true, "", "lines");
  ASSERT_EQ(sparse.x.size(), 3u);
  EXPECT_EQ(sparse.y, (std::vector<double>{1.0, 5.0, 14.0}));
  EXPECT_DOUBLE_EQ(sparse.x[1], peak_abs_difference(u[4], u[0]) / 4.0 * 1e3);
  EXPECT_DOUBLE_EQ(sparse.x[2], peak_abs_difference(u[13], u[4]) / 9.0 * 1e3);
}

// 14 actuators: two pages (10 and 4), each within a page's size, every actuator's two panels on
// exactly one of them; the envelope and the chosen floors' histories beside them.
TEST(ResponseEnvelopePlots, EveryActuatorIsDrawnOnPagesThatFitAPage) {
  const StudyOutcome outcome = run_study(tall_building());
  ASSERT_EQ(outcome.actuators.order.size(), static_cast<std::size_t>(kStoreys));
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_envelope_plots_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "actuators_3.png") << "stale";  // from a study of more actuators
  const std::vector<std::string> written = write_study_plots(outcome, dir);
  for (const char* figure :
       {"response_envelope.png", "floor_histories.png", "actuators_1.png", "actuators_2.png"})
    EXPECT_NE(std::find(written.begin(), written.end(), figure), written.end()) << figure;
  EXPECT_FALSE(std::filesystem::exists(dir / "actuators_3.png"));

  std::string pages;
  for (const char* page : {"actuators_1", "actuators_2", "response_envelope", "floor_histories"}) {
    const auto [width, height] = test::png_size(dir / (std::string(page) + ".png"));
    EXPECT_GT(width, 0u) << page;
    EXPECT_LE(width, 1800u) << page;
    EXPECT_LE(height, width * 1.42) << page;  // within an A4 page's proportions
  }
  const std::string first = test::read_text(dir / "actuators_1.svg"),
                    second = test::read_text(dir / "actuators_2.svg");
  for (int a = 0; a < kStoreys; ++a) {
    const std::string name =
        outcome.actuators.of(outcome.actuators.order[static_cast<std::size_t>(a)]);
    // Each panel's title starts with the actuator's name ("storey 1:", not "storey 10:").
    const std::string title = ">" + name + ":";
    EXPECT_EQ(count(a < kActuatorsPerPage ? first : second, title), 2u) << title;
    EXPECT_EQ(count(a < kActuatorsPerPage ? second : first, title), 0u) << title;
  }
  for (const std::string* page : {&first, &second})  // one legend a page, not one a panel
    for (const char* name : {">reference<", ">lag_2ms<"}) EXPECT_EQ(count(*page, name), 1u) << name;
  const std::string envelope = test::read_text(dir / "response_envelope.svg");
  EXPECT_NE(envelope.find("peak inter-storey drift (mm)"), std::string::npos);
  EXPECT_NE(envelope.find("reference: reference (drawn over)"), std::string::npos);
  const std::string histories = test::read_text(dir / "floor_histories.svg");
  for (int floor : {1, 4, 6, 9, 11, 14})
    EXPECT_EQ(count(histories, ": floor " + std::to_string(floor) + " (DOF "), 1u) << floor;
  EXPECT_EQ(count(histories, ": floor 2 (DOF "), 0u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::analysis
