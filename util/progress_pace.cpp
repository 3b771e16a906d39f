#include "util/progress_pace.h"

#include <chrono>
#include <utility>

namespace rths::util {

ProgressPace::ProgressPace(ProgressPacing pacing)
    : pacing_(std::move(pacing)), started_s_(now_s()) {}

double ProgressPace::now_s() const {
  if (pacing_.clock_s) return pacing_.clock_s();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double ProgressPace::elapsed() const { return now_s() - started_s_; }

std::optional<double> ProgressPace::due() {
  const double at = elapsed();
  if (at < pacing_.quiet) return std::nullopt;
  if (last_line_ >= 0.0 && at - last_line_ < pacing_.every) return std::nullopt;
  last_line_ = at;
  return at;
}

}  // namespace rths::util
