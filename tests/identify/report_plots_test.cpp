#include "identify/lab/report_plots.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>

#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(ReportPlotsTest, EveryPlotOfBothChannelsInTheLabsUnits) {
  GeneratorSpec spec;
  spec.duration = 12.0;
  spec.first_order_time_constant = 0.015;
  IdentifyOptions options;
  options.channels = {Channel::kMeasured, Channel::kForce};
  const Identification id = identify(generate_measured(spec), options);
  const auto dir = std::filesystem::temp_directory_path() / "rths_identify_report_plots_test";
  std::filesystem::remove_all(dir);
  const auto files = write_plots(id, dir);
  EXPECT_EQ(files.size(), 7u);
  EXPECT_NE(std::find(files.begin(), files.end(), dir / "measured_bode.png"), files.end());
  EXPECT_TRUE(std::filesystem::exists(dir / "measured_bode.svg"));
  for (const auto& f : files) {
    EXPECT_TRUE(std::filesystem::exists(f)) << f;
    EXPECT_GT(std::filesystem::file_size(f), 1000u) << f;
  }
  // Displacements in mm on every plot, and the tracking shown whole and zoomed to a few cycles.
  const auto text = [&](const char* name) {
    std::ifstream in(dir / name);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string tracking = text("measured_tracking.svg");
  EXPECT_NE(tracking.find("displacement (mm)"), std::string::npos);
  EXPECT_NE(tracking.find("zoom: the last"), std::string::npos);
  for (const char* entry : {">command<", ">measured<", ">declared model<", ">final model<"})
    EXPECT_EQ(count_of(tracking, entry), 2u) << entry;  // whole and zoomed
  EXPECT_NE(text("measured_residual_time.svg").find("residual (mm)"), std::string::npos);
  EXPECT_NE(text("force_loops.svg").find("measured displacement (mm)"), std::string::npos);
  EXPECT_EQ(tracking.find("(m)"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// A delay drifting by +/- 6 ms: the model's tau(t) and the per-window estimates both follow the
// truth, and the plot of them is written.
TEST(ReportPlotsTest, TimeVaryingDelayPlotFollowsTheDrift) {
  GeneratorSpec spec;
  spec.delay_drift = 0.006;
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  const Identification id = identify(generate_measured(spec), options);
  const auto& c = id.channels.at(0);
  ASSERT_TRUE(c.final_fit.model.has(Effect::kTimeVaryingDelay));
  const SignalScales sc = signal_scales(id.signals[0]);
  const ChannelModel constant = without_effect(c.final_fit.model, Effect::kTimeVaryingDelay, sc);
  const auto windows = windowed_estimate(
      constant, constant.index_of(Effect::kDelay, "delay", sc).value(), id.signals[0], 8);
  for (const auto& w : windows) {
    const double truth =
        spec.delay + spec.delay_drift * std::sin(2.0 * std::numbers::pi * w.time / spec.duration);
    EXPECT_NEAR(w.value, truth, 0.0015) << "window at " << w.time << " s";
    EXPECT_GT(w.std_error, 0.0);
  }
  const auto dir = std::filesystem::temp_directory_path() / "rths_identify_tv_delay_plot";
  std::filesystem::remove_all(dir);
  const auto files = write_plots(id, dir);
  const auto plot = dir / "measured_time_varying_delay.png";
  EXPECT_NE(std::find(files.begin(), files.end(), plot), files.end());
  EXPECT_GT(std::filesystem::file_size(plot), 1000u);
}

}  // namespace
}  // namespace rths::identify
