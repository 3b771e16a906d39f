// The joint network x actuator lag study on the paper's frame (in process; no namespaces needed).
#include "analysis/joint_lag/joint_lag.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/coupled_stability.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";
const std::filesystem::path kOut =
    std::filesystem::path(RTHS_BINARY_DIR) / "test_out" / "analysis" / "joint_lag";
constexpr double kMs = 1e-3;

JointLagStudy small_grid(JointLagStudy::ActuatorModel model) {
  JointLagStudy config;
  config.set_study("paper_frame.textproto");
  for (double r : {0.0, 0.004, 0.010}) config.add_network_round_trips(r);
  for (double a : {0.0, 0.006}) config.add_actuator_lags(a);
  config.set_actuator_model(model);
  return config;
}

const JointLagPoint& at(const JointLagResult& result, double network, double actuator) {
  for (const auto& p : result.grid) {
    if (std::abs(p.network_round_trip - network) < 1e-12 &&
        std::abs(p.actuator_lag - actuator) < 1e-12) {
      return p;
    }
  }
  throw std::runtime_error("no grid point");
}

TEST(JointLag, MeasuredTotalLagIsTheSumOfTheInjectedParts) {
  JointLagOptions options;
  options.output_directory = kOut / "shift";
  options.measure = false;
  const auto result = run_joint_lag(small_grid(JointLagStudy::SHIFT), kConfigs, options);
  ASSERT_EQ(result.grid.size(), 6u);
  for (const auto& p : result.grid) {
    ASSERT_FALSE(p.diverged);
    EXPECT_NEAR(p.measured_total_lag, p.network_round_trip + p.actuator_lag, 0.5 * kMs)
        << "R " << p.network_round_trip << " A " << p.actuator_lag;
  }
  EXPECT_DOUBLE_EQ(at(result, 0, 0).nrmse, 0.0);
  // The error grows with the total lag, and only the total matters for two pure shifts.
  EXPECT_GT(at(result, 0.004, 0).nrmse, 0.0);
  EXPECT_GT(at(result, 0.010, 0).nrmse, at(result, 0.004, 0).nrmse);
  EXPECT_GT(at(result, 0.010, 0.006).nrmse, at(result, 0.010, 0).nrmse);
  EXPECT_GT(at(result, 0.004, 0.006).nrmse, at(result, 0, 0.006).nrmse);
  EXPECT_EQ(result.measured_skipped, "the config asks for no across-sites runs");

  write_joint_lag_outputs(result, true);
  for (const char* file : {"grid.csv", "summary.json", "error_map.png", "error_map.svg",
                           "total_lag.png", "total_lag.svg"}) {
    EXPECT_GT(std::filesystem::file_size(result.output_directory / file), 100u) << file;
  }
  // The total-lag figure: its series in the legend, its axes in ms.
  std::ifstream in(result.output_directory / "total_lag.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* entry :
       {">in-process grid (J1 of realised vs command)<", ">measured = injected<",
        "injected network round trip + actuator lag (ms)", "measured total lag (ms)"})
    EXPECT_NE(svg.find(entry), std::string::npos) << entry;
}

// The grid judges divergence by the one rule every command uses (analysis::compare): 16 ms of
// network and 14 ms of actuator lag, past the frame's 24.2 ms, grow the peak far past 10x the
// lag-free run's, so the point is diverged as `rths sdof --delay 30ms` calls the same lag; and
// the map marks it, labels its contours and marks the cells past the boundary.
TEST(JointLag, APointPastTheBoundaryIsDivergedByTheOneRuleAndMarkedOnTheMap) {
  JointLagStudy config;
  config.set_study("paper_frame.textproto");
  for (double r : {0.0, 0.008, 0.016}) config.add_network_round_trips(r);
  for (double a : {0.0, 0.007, 0.014}) config.add_actuator_lags(a);
  JointLagOptions options;
  options.output_directory = kOut / "one_rule";
  options.measure = false;
  options.warn = [](const std::string&) {};
  const auto result = run_joint_lag(config, kConfigs, options);
  const JointLagPoint& past = at(result, 0.016, 0.014);
  EXPECT_TRUE(past.past_boundary);
  EXPECT_TRUE(past.diverged) << "E_rms " << past.rms_error_pct << " %, peak error "
                             << past.peak_error;
  EXPECT_FALSE(at(result, 0.016, 0.0).diverged);
  write_joint_lag_outputs(result, true);
  std::ifstream in(result.output_directory / "error_map.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(svg.find("diverged"), std::string::npos);
  EXPECT_NE(svg.find("E_rms (%), log scale"), std::string::npos) << "the map's colour is E_rms";
  EXPECT_EQ(svg.find("NRMSE"), std::string::npos);
  EXPECT_NE(svg.find("network round trip (ms)"), std::string::npos);
  EXPECT_NE(svg.find("actuator lag (ms)"), std::string::npos);
  std::ifstream gp(result.output_directory / "error_map.gp");
  const std::string script((std::istreambuf_iterator<char>(gp)), std::istreambuf_iterator<char>());
  EXPECT_NE(script.find("#440154"), std::string::npos) << "viridis, not a rainbow";
  EXPECT_EQ(script.find("rgbformulae"), std::string::npos);
  EXPECT_NE(script.find("with labels"), std::string::npos) << "contours carry their value";
  // Every layer in the legend; every cell whole (the axes reach half a cell past the grid).
  for (const char* entry : {"E_rms contours (%, labelled)", "stability boundary (continuous)",
                            "diverged (no colour: its error measures nothing)"})
    EXPECT_NE(svg.find(entry), std::string::npos) << entry;
  EXPECT_NE(script.find("set xrange [-4:20]"), std::string::npos) << script;
  EXPECT_NE(script.find("set yrange [-3.5:17.5]"), std::string::npos) << script;
  // Labelled contour levels, each label drawn: 1-2-5 steps up from the one below the smallest
  // bounded error (the lag-free corner aside) to the largest.
  std::ifstream labels_in(result.output_directory / "error_map_labels.dat");
  std::vector<double> levels;
  for (std::string line; std::getline(labels_in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double r = 0, a = 0, level = 0;
    fields >> r >> a >> level;
    levels.push_back(level);
    std::ostringstream label;
    label << '>' << level << " %<";
    EXPECT_NE(svg.find(label.str()), std::string::npos) << label.str();
  }
  double smallest = 1e300, largest = 0.0;
  for (const auto& p : result.grid)
    if (!p.diverged && p.rms_error_pct > 0.0) {
      smallest = std::min(smallest, p.rms_error_pct);
      largest = std::max(largest, p.rms_error_pct);
    }
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  ASSERT_GE(levels.size(), 2u);
  EXPECT_LT(levels.front(), smallest);
  EXPECT_GE(levels[1], smallest);
  EXPECT_LE(levels.back(), largest);
  // Every level labelled, the 1-2-5 steps between none left out.
  for (std::size_t i = 1; i < levels.size(); ++i)
    EXPECT_LE(levels[i] / levels[i - 1], 2.5 + 1e-9) << levels[i - 1] << " -> " << levels[i];
}

// A point past the stability boundary whose envelope grows exponentially is diverged even under
// the 10x rule, as `rths run` calls such a case diverging; inside the boundary it is not.
TEST(JointLag, PastTheBoundaryAGrowingEnvelopeIsDiverged) {
  const double dt = 0.01, period = 0.5;
  std::vector<double> reference, growing;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * dt, wave = std::sin(2.0 * M_PI * t / period);
    reference.push_back(wave);
    growing.push_back(std::exp(std::log(9.0) * t / 20.0) * wave);
  }
  JointLagPoint past;
  past.past_boundary = true;
  fill_joint_lag_errors(past, reference, growing, false, dt, period);
  EXPECT_TRUE(past.diverged);
  JointLagPoint inside;
  fill_joint_lag_errors(inside, reference, growing, false, dt, period);
  EXPECT_FALSE(inside.diverged);
}

TEST(JointLag, TheStabilityBoundaryIsTheCriticalDelayLessTheActuatorShift) {
  // A pure shift: network round trip + actuator lag enter as one delay, so the critical round trip
  // at actuator lag A is the frame's critical delay minus A (continuous, closed form).
  JointLagStudy config = small_grid(JointLagStudy::SHIFT);
  config.clear_network_round_trips();
  for (double r : {0.0, 0.012, 0.030}) config.add_network_round_trips(r);
  JointLagOptions options;
  options.output_directory = kOut / "boundary";
  options.measure = false;
  std::vector<std::string> warnings;
  options.warn = [&warnings](const std::string& w) { warnings.push_back(w); };
  const auto result = run_joint_lag(config, kConfigs, options);
  ASSERT_TRUE(result.boundary_skipped.empty()) << result.boundary_skipped;
  // The user is told before the grid runs how many points lie past the boundary (30 ms at both
  // actuator lags).
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("2 of 6 grid points lie past the stability boundary", 0), 0u)
      << warnings[0];
  ASSERT_GE(result.boundary.size(), 2u);
  const double critical = *result.boundary.front().critical_round_trip;
  EXPECT_NEAR(critical, 0.0242, 0.0005);  // the paper's frame: 24.2 ms
  for (const auto& b : result.boundary) {
    ASSERT_TRUE(b.critical_round_trip.has_value());
    EXPECT_NEAR(*b.critical_round_trip, critical - b.actuator_lag, 2e-4) << b.actuator_lag;
  }
  EXPECT_FALSE(at(result, 0.012, 0.006).past_boundary);
  EXPECT_TRUE(at(result, 0.030, 0.0).past_boundary);
  // Past the boundary the error grows far beyond the points inside it.
  const auto& past = at(result, 0.030, 0.006);
  EXPECT_TRUE(past.diverged || past.nrmse > 5 * at(result, 0.012, 0.006).nrmse)
      << past.nrmse << " vs " << at(result, 0.012, 0.006).nrmse;
  write_joint_lag_outputs(result, true);
  const std::string csv = [&] {
    std::ifstream in(result.output_directory / "grid.csv");
    std::string header;
    std::getline(in, header);
    return header;
  }();
  // E_peak and E_rms lead; the paper's NRMSE follows them.
  EXPECT_NE(csv.find(",peak_error_pct,rms_error_pct,"), std::string::npos) << csv;
  EXPECT_LT(csv.find(",rms_error_pct,"), csv.find(",nrmse_pct,")) << csv;
  EXPECT_NE(csv.find("past_stability_boundary"), std::string::npos) << csv;
  // The map draws the boundary and marks the diverged points.
  std::ifstream boundary(result.output_directory / "error_map_boundary.dat");
  std::string line;
  int rows = 0;
  while (std::getline(boundary, line)) rows += line.empty() || line[0] == '#' ? 0 : 1;
  EXPECT_EQ(rows, static_cast<int>(result.boundary.size()));
}

// With a force predictor whose model is 40 % soft and never fitted, the compensated loop's
// critical lag of the measured pair is about 67 ms (core::predictor_critical_delay): the map's
// points inside that boundary stay bounded far past the plain loop's 24 ms, those beyond it
// diverge, and the map draws both boundaries.
TEST(JointLag, APredictorMovesTheBoundaryToItsModelsCriticalLag) {
  JointLagStudy config;
  config.set_study("paper_frame.textproto");
  for (double r : {0.0, 0.040, 0.090}) config.add_network_round_trips(r);
  for (double a : {0.0, 0.014}) config.add_actuator_lags(a);
  config.mutable_force_predictor()->set_stiffness_factor(0.6);
  config.mutable_force_predictor()->set_fixed_model(true);
  JointLagOptions options;
  options.output_directory = kOut / "predictor";
  options.measure = false;
  std::vector<std::string> warnings;
  options.warn = [&warnings](const std::string& w) { warnings.push_back(w); };
  const auto result = run_joint_lag(config, kConfigs, options);
  ASSERT_EQ(result.compensated_boundary.size(), result.boundary.size());
  const double compensated = *result.compensated_boundary.front().critical_round_trip;
  EXPECT_NEAR(compensated, 0.067, 0.003);
  for (const auto& b : result.compensated_boundary)
    EXPECT_NEAR(*b.critical_round_trip, std::max(0.0, compensated - b.actuator_lag), 1e-12);
  EXPECT_NE(result.compensated_boundary_note.find("-40 %"), std::string::npos)
      << result.compensated_boundary_note;
  // 54 ms of lag in all: past the plain loop's boundary, inside the predictor's.
  const JointLagPoint& inside = at(result, 0.040, 0.014);
  EXPECT_FALSE(inside.past_boundary);
  EXPECT_FALSE(inside.diverged) << "E_rms " << inside.rms_error_pct << " %";
  EXPECT_TRUE(at(result, 0.090, 0.0).past_boundary);
  EXPECT_TRUE(at(result, 0.090, 0.014).diverged);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("2 of 6 grid points", 0), 0u) << warnings[0];
  EXPECT_NE(to_text(result).find("every grid point runs with a force predictor"),
            std::string::npos);
  EXPECT_TRUE(to_json(result).contains("compensated_stability_boundary"));
  write_joint_lag_outputs(result, true);
  std::ifstream in(result.output_directory / "error_map.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(svg.find("stability boundary with the predictor"), std::string::npos);
  EXPECT_NE(svg.find("stability boundary without the predictor (continuous)"), std::string::npos);
}

// The grid's table: a cell per point, E_rms (%) and the measured total lag (ms) to 2 decimals.
TEST(JointLag, TheGridTableStatesEachCellToTwoDecimals) {
  JointLagResult result;
  result.study_name = "paper_frame";
  JointLagPoint p;
  p.network_round_trip = 0.014;
  p.actuator_lag = 0.008;
  p.rms_error_pct = 7.3512;
  p.measured_total_lag = 0.02251;
  result.grid.push_back(p);
  p.actuator_lag = 0.016;
  p.diverged = true;
  result.grid.push_back(p);
  const std::string text = to_text(result);
  EXPECT_NE(text.find("7.35 [22.51]"), std::string::npos) << text;
  EXPECT_NE(text.find("diverged"), std::string::npos) << text;
}

// An across-sites point's E_rms covers only its shorter run: it is printed beside the in-process
// run of the same stretch. A lockstep run with network lag says plainly that the lag never reaches
// its response, so it cannot check the map's network axis; a real-time one compares both lags.
TEST(JointLag, TheAcrossSitesLineComparesLikeWithLikeAndSaysWhatLockstepCannotCheck) {
  JointLagResult result;
  result.study_name = "paper_frame";
  JointLagPoint p;
  p.network_round_trip = 0.014;
  p.actuator_lag = 0.008;
  p.rms_error_pct = 7.35;
  p.in_process_rms_error_pct = 7.35;
  p.duration = 1.0;
  result.measured.push_back(p);
  p.real_time = true;
  p.rms_error_pct = 52.0;
  p.in_process_rms_error_pct = 50.0;
  result.measured.push_back(p);
  const std::string text = to_text(result);
  EXPECT_NE(text.find("across sites (lockstep): injected 14.00 ms network + 8.00 ms actuator"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("E_rms 7.35 % over the first 1.00 s against 7.35 % in process for the "
                      "actuator lag alone over the same 1.00 s"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("E_rms 52.00 % over the first 1.00 s against 50.00 % in process for the "
                      "same lags over the same 1.00 s"),
            std::string::npos)
      << text;
  const std::string plainly =
      "never reaches the response: this run checks the distributed "
      "machinery, not the map's network axis";
  const auto said = text.find(plainly);
  ASSERT_NE(said, std::string::npos) << text;
  EXPECT_EQ(text.find(plainly, said + 1), std::string::npos) << "the real-time run can check it";
  EXPECT_EQ(diverged_points(result), 0u);
  result.measured[1].diverged = true;
  p.diverged = true;
  result.grid.push_back(p);
  EXPECT_EQ(diverged_points(result), 2u);
}

TEST(JointLag, FirstOrderActuatorLagsByAboutItsTimeConstant) {
  JointLagOptions options;
  options.output_directory = kOut / "first_order";
  options.measure = false;
  const auto result = run_joint_lag(small_grid(JointLagStudy::FIRST_ORDER), kConfigs, options);
  const auto& p = at(result, 0.004, 0.006);
  // At the frame's 2 Hz the phase lag of a 6 ms first-order lag is atan(w T)/w ~ 6 ms.
  EXPECT_NEAR(p.measured_total_lag, 0.010, 1 * kMs);
}

// The across-sites part is a runner handed in (deploy's, in `rths joint-lag`): whether it runs,
// why not, and that its points are counted in the progress.
JointLagStudy with_measured_points() {
  JointLagStudy config;
  config.set_study("paper_frame.textproto");
  config.add_network_round_trips(0.004);
  config.add_actuator_lags(0.002);
  config.set_sites("sites_paper_frame.textproto");
  for (double r : {0.0, 0.014}) config.add_measured_network_round_trips(r);
  config.add_measured_actuator_lags(0.008);
  return config;
}

TEST(JointLag, AcrossSitesRunsOnlyWhenAskedAndPossibleAndCountsInTheProgress) {
  std::size_t runs = 0;
  JointLagOptions options;
  options.output_directory = kOut / "across_sites";
  std::optional<std::string> unavailable = "namespaces are not permitted here";
  options.across_sites.unavailable = [&] { return unavailable; };
  options.across_sites.run = [&](const JointLagStudy& config, const std::filesystem::path& base_dir,
                                 JointLagResult& result, const std::function<void()>& one_done) {
    ++runs;
    EXPECT_EQ(base_dir, kConfigs);
    EXPECT_EQ(result.output_directory, kOut / "across_sites");
    for (const double r : config.measured_network_round_trips()) {
      JointLagPoint point;
      point.network_round_trip = r;
      point.actuator_lag = config.measured_actuator_lags(0);
      result.measured.push_back(point);
      one_done();
    }
  };
  std::vector<std::pair<std::size_t, std::size_t>> progress;
  options.progress = [&](std::size_t done, std::size_t total) {
    progress.emplace_back(done, total);
  };
  const JointLagStudy config = with_measured_points();

  // Impossible here: skipped with the runner's reason; only the grid point counts.
  JointLagResult result = run_joint_lag(config, kConfigs, options);
  EXPECT_EQ(result.measured_skipped, "namespaces are not permitted here");
  EXPECT_EQ(runs, 0u);
  EXPECT_EQ(progress.back(), std::make_pair(std::size_t{1}, std::size_t{1}));

  // Not requested, or no runner: skipped, saying which.
  unavailable.reset();
  options.measure = false;
  EXPECT_EQ(run_joint_lag(config, kConfigs, options).measured_skipped,
            "across-sites runs not requested (--no-measure)");
  options.measure = true;
  JointLagOptions without_runner = options;
  without_runner.across_sites = {};
  EXPECT_NE(run_joint_lag(config, kConfigs, without_runner)
                .measured_skipped.find("no across-sites runner"),
            std::string::npos);
  EXPECT_EQ(runs, 0u);

  // Possible: the runner's points are in the result and in the progress (1 grid + 2 measured).
  progress.clear();
  result = run_joint_lag(config, kConfigs, options);
  EXPECT_TRUE(result.measured_skipped.empty()) << result.measured_skipped;
  EXPECT_EQ(runs, 1u);
  ASSERT_EQ(result.measured.size(), 2u);
  EXPECT_EQ(result.measured[1].network_round_trip, 0.014);
  ASSERT_EQ(progress.size(), 3u);
  EXPECT_EQ(progress.back(), std::make_pair(std::size_t{3}, std::size_t{3}));
}

TEST(JointLag, ConfigErrorsNameTheField) {
  const auto path = std::filesystem::temp_directory_path() / "rths_joint_lag_bad.textproto";
  {
    std::ofstream out(path);
    out << "study: \"paper_frame.textproto\"\nnetwork_round_trips: [0, -0.01]\nactuator_lags: 0\n";
  }
  try {
    load_joint_lag(path);
    FAIL() << "negative lag accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("network_round_trips"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(load_joint_lag(kConfigs / "joint_lag_study.textproto"));
}

// On a structure of several DOFs (the lab's frame with its storey specimen) the plain boundary is
// not drawn, the predictor's is: the coupled loop's critical lag of the measured pair (its model
// twice the specimen's stiffness, frozen; the part built by hand here) less the actuator lag, at
// lags from 0 to the largest. Points past it are flagged; 60 ms in all (20 % past) diverges. (Far
// past it, at 80 ms, this loop is stable again: the verdict calls every lag past the first
// crossing unstable.)
TEST(JointLag, APredictorsBoundaryIsDrawnForSeveralDofs) {
  JointLagStudy config;
  config.set_study("frame3_storey_specimen.textproto");
  for (double r : {0.0, 0.030, 0.050}) config.add_network_round_trips(r);
  for (double a : {0.0, 0.010}) config.add_actuator_lags(a);
  config.mutable_force_predictor()->set_stiffness_factor(2.0);
  config.mutable_force_predictor()->set_fixed_model(true);
  JointLagOptions options;
  options.output_directory = kOut / "predictor_frame3";
  options.measure = false;
  const auto result = run_joint_lag(config, kConfigs, options);
  EXPECT_FALSE(result.boundary_skipped.empty());
  const study::PreparedStudy prepared = study::prepare_study(
      study::load_study(kConfigs / "frame3_storey_specimen.textproto"), kConfigs);
  core::DelayedPart storey;
  storey.row = core::Vec::Unit(3, 1) - core::Vec::Unit(3, 0);
  storey.stiffness = 0.3e6;
  storey.predicted = true;
  storey.model_stiffness = 0.6e6;
  const core::StructuralModel& model = prepared.base.model;
  const auto loop = core::coupled_loop_stability(model, {storey},
                                                 core::modal_analysis(model.mass, model.stiffness));
  ASSERT_TRUE(loop.common_critical_lag.has_value());
  ASSERT_EQ(result.compensated_boundary.size(), 41u);
  EXPECT_DOUBLE_EQ(result.compensated_boundary.back().actuator_lag, 0.010);
  for (const auto& b : result.compensated_boundary)
    EXPECT_NEAR(*b.critical_round_trip, std::max(0.0, *loop.common_critical_lag - b.actuator_lag),
                1e-12);
  EXPECT_NE(result.compensated_boundary_note.find("critical lag of the measured pair"),
            std::string::npos)
      << result.compensated_boundary_note;
  EXPECT_FALSE(at(result, 0.030, 0.010).past_boundary);
  EXPECT_FALSE(at(result, 0.030, 0.010).diverged);
  EXPECT_TRUE(at(result, 0.050, 0.010).past_boundary);
  EXPECT_TRUE(at(result, 0.050, 0.010).diverged) << at(result, 0.050, 0.010).rms_error_pct;
}

}  // namespace
}  // namespace rths::analysis
