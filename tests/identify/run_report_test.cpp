// The figures of a run's identification: one PNG and its SVG per figure, the response and shares
// figures only with a residual.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include <unistd.h>
#include <filesystem>

#include "identify/run/run_report.h"

namespace rths::identify {
namespace {

namespace fs = std::filesystem;

RunIdentification small_run() {
  RunIdentification run;
  NetworkPath link;
  link.node_id = 1;
  for (int i = 0; i < 100; ++i) {
    const double t = 0.01 * i;
    link.time.push_back(t);
    link.injected.push_back(0.002);
    link.round_trip.push_back(0.002 + 0.001 * t);
    link.model.push_back(0.002 + 0.001 * t);
  }
  link.effects.push_back({"drifting delay", "1 ms", 5e-4, 1e-5, 1.0});
  run.links.push_back(link);
  return run;
}

RunResidual small_residual() {
  RunResidual r;
  r.steps = 100;
  r.floors.push_back({1, 0.4, 0.01});
  r.declared = 0.4;
  r.identified = 0.01;
  r.links.push_back({"actuator 1", "all", 0.39, 1.0});
  r.effects.push_back({"actuator 1", "first_order", 0.39, 1.0});
  r.recorded_response.resize(100, 1);
  r.declared_response.resize(100, 1);
  r.identified_response.resize(100, 1);
  for (int k = 0; k < 100; ++k) {
    r.time.push_back(0.01 * k);
    r.recorded_response(k, 0) = std::sin(0.1 * k) * 1e-3;
    r.declared_response(k, 0) = std::sin(0.1 * k - 0.2) * 1e-3;
    r.identified_response(k, 0) = r.recorded_response(k, 0);
  }
  return r;
}

TEST(RunReport, WritesEachFigureAsPngAndSvg) {
  const fs::path dir = fs::temp_directory_path() / ("rths_run_report_" + std::to_string(getpid()));
  fs::remove_all(dir);
  RunIdentification run = small_run();
  auto written = write_run_plots(run, dir);
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0].filename(), "record_lag.png");
  run.residual = small_residual();
  written = write_run_plots(run, dir);
  ASSERT_EQ(written.size(), 3u);
  // A lab's record made by another controller has no links: no lag figure, the others still.
  RunIdentification without_links = run;
  without_links.links.clear();
  const fs::path bare = dir / "without_links";
  const auto bare_written = write_run_plots(without_links, bare);
  ASSERT_EQ(bare_written.size(), 2u);
  EXPECT_EQ(bare_written[0].filename(), "record_response.png");
  EXPECT_FALSE(fs::exists(bare / "record_lag.png"));
  for (const auto& png : written) {
    EXPECT_GT(fs::file_size(png), 1000u) << png;
    EXPECT_TRUE(fs::exists(fs::path(png).replace_extension(".svg"))) << png;
  }
  // Every series in the legend and every axis with its unit. The lag panel's three series agree
  // here (model = measured): drawn wide to narrow, the injected band first and the model dashed
  // last, so none hides another.
  const auto svg = [&](const char* name) {
    std::ifstream in(dir / name);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string lag = svg("record_lag.svg");
  std::size_t previous = 0;
  for (const char* entry :
       {">injected by the node<", ">measured round trip<", ">identified model<"}) {
    const auto at = lag.find(entry);
    ASSERT_NE(at, std::string::npos) << entry;
    EXPECT_GT(at, previous) << entry << " drawn out of order";
    previous = at;
  }
  for (const char* axis : {"lag (ms)", "time (s)"}) EXPECT_NE(lag.find(axis), std::string::npos);
  EXPECT_NE(lag.find("stroke-width=\"6.00\""), std::string::npos);
  const std::string response = svg("record_response.svg");
  for (const char* entry : {">recorded<", ">declared model (NRMSE ", ">identified model (NRMSE ",
                            ">declared - recorded<", ">identified - recorded<", "displacement (mm)",
                            "error (mm)", "time (s)"})
    EXPECT_NE(response.find(entry), std::string::npos) << entry;
  const std::string shares = svg("record_shares.svg");
  for (const char* entry :
       {"actuator 1 (its whole identified rig), share", "actuator 1: first_order, share",
        "remaining: the identified model's NRMSE", "NRMSE removed (%)"})
    EXPECT_NE(shares.find(entry), std::string::npos) << entry;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rths::identify
