#pragma once
// A study's progress while it runs (analysis::run_study): one line at a time through a callback
// (stderr in `rths run`), only for a run that has lasted `quiet` seconds, then at most one every
// `every` seconds, so that a short run prints none and a long one a few:
//   "progress: run 2 of 3 (case 'lag_14ms'), step 40960 of 81920; 12.3 s so far, about 12 s left"
// Inputs: the simulations the study runs (the lag-free run and each case that adds to it), each
// of `steps` steps. The time left is the steps left at the rate so far (steps a
// second over every simulation run since start()), wall time by steady_clock. The clock is read
// every kClockSteps steps, so the loop's cost is a counter's; when a line is due is
// util::ProgressPace's rule.

#include <cstddef>
#include <functional>
#include <string>

#include "core/simulation.h"
#include "util/progress_pace.h"

namespace rths::analysis {

struct ProgressOptions {
  std::function<void(const std::string&)> print = {};  // none: nothing is printed
  double quiet = 3.0;                                  // s before the first line
  double every = 5.0;                                  // s at least between lines
  // Seconds on a monotonic clock; none: steady_clock. Tests give their own, so that what a line
  // says never depends on how busy the machine is.
  std::function<double()> clock_s = {};
};

class RunProgress : public core::StepHooks {
 public:
  static constexpr std::size_t kClockSteps = 1024;

  // `simulations` runs of `steps` steps each (> 0); the clock starts now.
  RunProgress(ProgressOptions options, std::size_t simulations, std::size_t steps);

  // Simulation `index` (0-based, < simulations) starts, named `name` ("case 'lag_14ms'").
  void start(std::size_t index, std::string name);

  bool after_step(std::size_t k, const core::SimulationResult& result) override;

  // Lines printed so far.
  std::size_t lines() const { return lines_; }

 private:
  void print_line(std::size_t k, double elapsed);

  std::function<void(const std::string&)> print_;
  util::ProgressPace pace_;  // its clock starts at construction
  std::size_t simulations_, steps_;
  std::size_t index_ = 0;
  std::string name_;
  std::size_t lines_ = 0;
};

}  // namespace rths::analysis
