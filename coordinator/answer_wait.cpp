#include "coordinator/answer_wait.h"

#include <algorithm>

namespace rths::coordinator {

std::optional<AnswerWait::Switch> AnswerWait::step(double round_trip) {
  ring_[next_] = round_trip;
  next_ = (next_ + 1) % kJudged;
  ++since_switch_;
  if (since_switch_ < settle_ || since_switch_ % kJudged != 0) return std::nullopt;
  std::array<double, kJudged> sorted = ring_;
  std::nth_element(sorted.begin(), sorted.begin() + kJudged / 2, sorted.end());
  const double median = sorted[kJudged / 2];
  const bool change = waiting_ ? median > wait_ : median < wait_ / 4;
  if (!change) return std::nullopt;
  waiting_ = !waiting_;
  since_switch_ = 0;
  settle_ = settle_ == kJudged ? kSettle : 2 * settle_;
  return Switch{waiting_, median};
}

}  // namespace rths::coordinator
