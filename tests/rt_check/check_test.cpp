// platform/check: the summary a run records, its text and JSON, and reading a saved check back.
#include "rt_check/check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

namespace rths::rt_check {
namespace {

using ::testing::HasSubstr;

runtime::PlatformSummary summary_of_a_stalling_vm() {
  WakeupSamples samples;
  samples.cpus = {0, 1};
  samples.rate_hz = 1024;
  samples.seconds = 10;
  samples.lateness.assign(2, std::vector<double>(10240, 40e-6));
  for (int i = 0; i < 10; ++i) samples.lateness[1][static_cast<std::size_t>(i) * 1000] = 3.2e-3;
  PlatformFacts facts;
  facts.kernel = "Linux version 6.18 SMP PREEMPT_DYNAMIC";
  facts.preemption = "PREEMPT_DYNAMIC";
  facts.governor = "none (no cpufreq)";
  facts.online_cpus = {0, 1};
  facts.memlock_limit_bytes = 8 << 20;
  const LatencyStats stats(samples);
  FailSafeInput in;
  in.dt = 1.0 / 1024;
  in.run_seconds = 15;
  in.cpus = {0, 1};
  return make_summary(facts, stats, samples, in, judge_failsafe(stats, facts, in));
}

TEST(PlatformSummary, CarriesTheFactsTheFiguresAndTheVerdict) {
  const runtime::PlatformSummary s = summary_of_a_stalling_vm();
  EXPECT_EQ(s.measured_cpus(), "0,1");
  EXPECT_EQ(s.wakeups(), 20480u);
  EXPECT_DOUBLE_EQ(s.lateness_median(), 40e-6);
  EXPECT_DOUBLE_EQ(s.lateness_max(), 3.2e-3);
  EXPECT_DOUBLE_EQ(s.stalls_over_1ms_per_minute(), 30.0);  // 10 in 20 CPU-seconds
  EXPECT_DOUBLE_EQ(s.stalls_over_5ms_per_minute(), 0.0);
  EXPECT_NEAR(s.window_ms(), 3 * 1000.0 / 1024, 1e-9);
  EXPECT_TRUE(s.refused());
  EXPECT_THAT(s.verdict(), HasSubstr("does NOT hold"));
  const std::string text = summary_text(s);
  EXPECT_THAT(text, HasSubstr("preemption: PREEMPT_DYNAMIC"));
  EXPECT_THAT(text, HasSubstr("memlock 8388608 bytes, rtprio unlimited"));
  EXPECT_THAT(text, HasSubstr("max 3200 us"));
}

TEST(PlatformSummary, JsonRoundTripsAndReadsRtChecksOutput) {
  const runtime::PlatformSummary s = summary_of_a_stalling_vm();
  const nlohmann::json j = summary_json(s);
  EXPECT_TRUE(j.contains("lateness_p9999"));
  EXPECT_TRUE(j.at("refused").get<bool>());
  EXPECT_EQ(summary_from_json(j).SerializeAsString(), s.SerializeAsString());
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_check_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "rt_check.json") << nlohmann::json{{"platform", j}, {"holds", false}}.dump();
  std::ofstream(dir / "bare.json") << j.dump();
  std::ofstream(dir / "bad.json") << "{\"lateness_max\": \"soon\"}";
  EXPECT_EQ(read_summary_file(dir / "rt_check.json").lateness_max(), s.lateness_max());
  EXPECT_EQ(read_summary_file(dir / "bare.json").verdict(), s.verdict());
  EXPECT_THROW(read_summary_file(dir / "bad.json"), std::invalid_argument);
  try {
    read_summary_file(dir / "none.json");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("none.json"));
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::rt_check
