#pragma once
// When a long job's next progress line is due: none before it has lasted `quiet` seconds, then
// at most one every `every` seconds, so that a short job prints none and a long one a few.
// Shared by a study's run progress (analysis/study_run/run_progress.h) and a node's set-up
// progress (runtime/node/setup_progress.h). Time: seconds on a monotonic clock, steady_clock
// unless the caller gives its own (tests do, so that a line never depends on the machine's load).

#include <functional>
#include <optional>

namespace rths::util {

struct ProgressPacing {
  double quiet = 3.0;                    // s before the first line
  double every = 5.0;                    // s at least between lines
  std::function<double()> clock_s = {};  // none: steady_clock
};

class ProgressPace {
 public:
  // The job starts now (the clock is read once).
  explicit ProgressPace(ProgressPacing pacing);

  // Seconds since the start when a line is due now (the line is then taken as printed), else
  // nullopt. Reads the clock once.
  std::optional<double> due();
  // Seconds since the start. Reads the clock once.
  double elapsed() const;
  // Whether a line was ever due (the job outlasted its quiet time when asked).
  bool spoke() const { return last_line_ >= 0.0; }

 private:
  double now_s() const;

  ProgressPacing pacing_;
  double started_s_ = 0.0;
  double last_line_ = -1.0;  // s since the start of the last line; < 0: none yet
};

}  // namespace rths::util
