#include "analysis/study_run/run_progress.h"

#include <cstdio>
#include <utility>

namespace rths::analysis {

RunProgress::RunProgress(ProgressOptions options, std::size_t simulations, std::size_t steps)
    : options_(std::move(options)), simulations_(simulations), steps_(steps), started_s_(now_s()) {}

double RunProgress::now_s() const {
  if (options_.clock_s) return options_.clock_s();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void RunProgress::start(std::size_t index, std::string name) {
  index_ = index;
  name_ = std::move(name);
}

bool RunProgress::after_step(std::size_t k, const core::SimulationResult& /*result*/) {
  if (!options_.print || k == 0 || k % kClockSteps != 0) return true;
  const double elapsed = now_s() - started_s_;
  if (elapsed < options_.quiet) return true;
  if (last_line_ >= 0.0 && elapsed - last_line_ < options_.every) return true;
  print_line(k, elapsed);
  last_line_ = elapsed;
  return true;
}

void RunProgress::print_line(std::size_t k, double elapsed) {
  const double done = static_cast<double>(index_ * steps_ + k);
  const double total = static_cast<double>(simulations_ * steps_);
  const double left = done > 0.0 ? elapsed * (total - done) / done : 0.0;
  char line[160];
  std::snprintf(line, sizeof line, "step %zu of %zu; %.1f s so far, about %.0f s left", k, steps_,
                elapsed, left);
  options_.print("progress: run " + std::to_string(index_ + 1) + " of " +
                 std::to_string(simulations_) + " (" + name_ + "), " + line);
  ++lines_;
}

}  // namespace rths::analysis
