#include "analysis/study_run/run_progress.h"

#include <cstdio>
#include <optional>
#include <utility>

namespace rths::analysis {

RunProgress::RunProgress(ProgressOptions options, std::size_t simulations, std::size_t steps)
    : print_(std::move(options.print)),
      pace_({options.quiet, options.every, std::move(options.clock_s)}),
      simulations_(simulations),
      steps_(steps) {}

void RunProgress::start(std::size_t index, std::string name) {
  index_ = index;
  name_ = std::move(name);
}

bool RunProgress::after_step(std::size_t k, const core::SimulationResult& /*result*/) {
  if (!print_ || k == 0 || k % kClockSteps != 0) return true;
  if (const std::optional<double> elapsed = pace_.due()) print_line(k, *elapsed);
  return true;
}

void RunProgress::print_line(std::size_t k, double elapsed) {
  const double done = static_cast<double>(index_ * steps_ + k);
  const double total = static_cast<double>(simulations_ * steps_);
  const double left = done > 0.0 ? elapsed * (total - done) / done : 0.0;
  char line[160];
  std::snprintf(line, sizeof line, "step %zu of %zu; %.1f s so far, about %.0f s left", k, steps_,
                elapsed, left);
  print_("progress: run " + std::to_string(index_ + 1) + " of " + std::to_string(simulations_) +
         " (" + name_ + "), " + line);
  ++lines_;
}

}  // namespace rths::analysis
