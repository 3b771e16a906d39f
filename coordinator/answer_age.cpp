#include "coordinator/answer_age.h"

#include <algorithm>
#include <cmath>

#include "runtime/node/plan.h"

namespace rths::coordinator {

AnswerWindow::AnswerWindow(const config::Deployment& deployment, const config::NodeSpec& spec,
                           double dt)
    : dt_(dt), missed_(runtime::max_missed_answers(deployment, dt)) {
  for (const config::LinkLag* lag : {&spec.receive_lag(), &spec.send_lag()}) {
    fixed_ += lag->one_way_delay() + 5.0 * lag->jitter() + lag->network().spike_delay();
    drift_rate_ += lag->network().drift_rate();
  }
}

std::int64_t AnswerWindow::steps(double time) const {
  const double injected = fixed_ + drift_rate_ * std::max(0.0, time);
  // A lag of whole steps within rounding is that many steps, not one more.
  return missed_ + static_cast<std::int64_t>(std::ceil(injected / dt_ - 1e-9));
}

void AnswerAgeTally::step(std::int64_t age) {
  const std::int64_t a = std::max<std::int64_t>(age, 0);
  ++counts_[std::min<std::size_t>(static_cast<std::size_t>(a), kBins - 1)];
  ++steps_;
  max_ = std::max(max_, a);
}

runtime::AnswerAge AnswerAgeTally::summary(double window_steps, double dt) const {
  runtime::AnswerAge out;
  out.set_steps_judged(steps_);
  out.set_window_steps(window_steps);
  out.set_dt(dt);
  if (steps_ == 0) return out;
  // The smallest age with at least q of the steps at or below it.
  const auto quantile = [this](double q) {
    const auto need = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(steps_)));
    std::uint64_t seen = 0;
    for (std::size_t k = 0; k < kBins; ++k) {
      seen += counts_[k];
      if (seen >= std::max<std::uint64_t>(need, 1)) return static_cast<double>(k);
    }
    return static_cast<double>(kBins - 1);
  };
  out.set_median_steps(quantile(0.5));
  out.set_p99_steps(quantile(0.99));
  out.set_max_steps(static_cast<double>(max_));
  return out;
}

}  // namespace rths::coordinator
