// A study's progress lines (analysis/study_run/run_progress.h): a run past its quiet time says which run,
// which step and the time left, at the clock's rate; a short one prints nothing; run_study names
// the lag-free run and each case that adds to it.
#include "analysis/study_run/run_progress.h"

#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/study_run/study_run.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kConfigs = RTHS_SOURCE_DIR "/configs";

// A clock that moves `step_s` seconds each time it is read (the constructor reads it once).
std::function<double()> ticking_clock(double step_s) {
  return [now = 0.0, step_s]() mutable { return now += step_s; };
}

// An SDOF, all of it experimental, `duration` s of El Centro at 1 ms: a reference that adds
// nothing to the lag-free run and a case with 5 ms of lag.
study::PreparedStudy sdof(double duration) {
  const std::string text =
      "name: \"sdof\" structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } } "
      "motion { path: \"../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: " +
      std::to_string(duration) +
      " } integrator { dt: 0.001 } substructuring { experimental_fraction: 0.5 } "
      "cases { name: \"reference\" } cases { name: \"lag_5ms\" delay { shift { delay: 0.005 } } }";
  return study::prepare_study(study::parse_study(text, "test"), kConfigs);
}

TEST(RunProgress, PastItsQuietTimeALineEveryClockReadNamesTheRunTheStepAndTheTimeLeft) {
  std::vector<std::string> lines;
  RunProgress progress({.print = [&](const std::string& l) { lines.push_back(l); },
                        .quiet = 0.0,
                        .every = 0.0,
                        .clock_s = ticking_clock(1.0)},
                       3, 4096);
  progress.start(1, "case 'lag'");
  const core::SimulationResult unused;
  for (std::size_t k = 0; k < 4096; ++k) EXPECT_TRUE(progress.after_step(k, unused));
  ASSERT_EQ(lines.size(), 3u);  // steps 1024, 2048 and 3072
  EXPECT_EQ(progress.lines(), 3u);
  EXPECT_EQ(lines[1].rfind("progress: run 2 of 3 (case 'lag'), step 2048 of 4096; ", 0), 0u)
      << lines[1];
  // Second read, at step 2048 of run 2: 2 s so far for 6144 of 3 x 4096 steps, 2 s left at that
  // rate.
  EXPECT_NE(lines[1].find("; 2.0 s so far, about 2 s left"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find(" s left"), std::string::npos) << lines[1];
}

TEST(RunProgress, ARunShorterThanItsQuietTimePrintsNothing) {
  std::vector<std::string> lines;
  RunProgress progress(
      {.print = [&](const std::string& l) { lines.push_back(l); }, .clock_s = ticking_clock(0.3)},
      1, 8192);
  progress.start(0, "the lag-free run");
  const core::SimulationResult unused;
  for (std::size_t k = 0; k < 8192; ++k) progress.after_step(k, unused);
  EXPECT_TRUE(lines.empty()) << lines.front();  // 8 reads: 2.4 s, inside the 3 s quiet time
}

TEST(RunProgress, PastItsQuietTimeALineAtMostEveryFiveSeconds) {
  std::vector<std::string> lines;
  RunProgress progress(
      {.print = [&](const std::string& l) { lines.push_back(l); }, .clock_s = ticking_clock(1.0)},
      1, 16 * RunProgress::kClockSteps);
  progress.start(0, "the lag-free run");
  const core::SimulationResult unused;
  for (std::size_t k = 0; k < 16 * RunProgress::kClockSteps; ++k) progress.after_step(k, unused);
  // Reads at 1, 2, ... 15 s: a line at 3 s, then at 8 and 13.
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_NE(lines[0].find("step 3072 of 16384; 3.0 s so far"), std::string::npos) << lines[0];
  EXPECT_NE(lines[2].find("step 13312 of 16384; 13.0 s so far"), std::string::npos) << lines[2];
}

TEST(RunProgress, RunStudyReportsTheLagFreeRunAndEachCaseThatAddsToIt) {
  std::vector<std::string> lines;
  run_study(sdof(5.0), {.progress = {.print = [&](const std::string& l) { lines.push_back(l); },
                                     .quiet = 0.0,
                                     .every = 0.0}});
  // 5000 steps each: lines at steps 1024, 2048, 3072 and 4096 of the lag-free run and of the
  // lagged case; the reference adds nothing (it is the lag-free run) and runs no steps.
  ASSERT_EQ(lines.size(), 8u);
  EXPECT_EQ(lines[0].rfind("progress: run 1 of 2 (the lag-free run), step 1024 of 5000; ", 0), 0u)
      << lines[0];
  EXPECT_EQ(lines[7].rfind("progress: run 2 of 2 (case 'lag_5ms'), step 4096 of 5000; ", 0), 0u)
      << lines[7];
}

TEST(RunProgress, AShortStudyWithTheDefaultsPrintsNothing) {
  std::vector<std::string> lines;
  run_study(sdof(2.0), {.progress = {.print = [&](const std::string& l) { lines.push_back(l); },
                                     .clock_s = ticking_clock(0.5)}});
  EXPECT_TRUE(lines.empty()) << lines.front();
}

}  // namespace
}  // namespace rths::analysis
