#include "core/link_answers.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/time_text.h"

namespace rths::core {

LinkWayLag::LinkWayLag(const LinkWay& way, double dt) : way_(way), dt_(dt), rng_(way.seed) {}

std::optional<std::int64_t> LinkWayLag::release(std::int64_t arrival_ns, std::int64_t step) {
  // The draws in runtime::LagInjector's order, each only when its term is on, so a way's
  // sequence is the same one a node injecting this lag draws.
  if (way_.loss > 0 && uniform_(rng_) < way_.loss) return std::nullopt;
  double delay = way_.one_way_delay;
  if (way_.jitter > 0) delay = std::max(0.0, delay + way_.jitter * normal_(rng_));
  if (way_.drop_steps > 0 && step >= way_.drop_first_step &&
      step < way_.drop_first_step + way_.drop_steps)
    return std::nullopt;
  // A message of no step (step < 0) gets the link's lag and jitter, not its emulated extra.
  double extra = 0.0;
  if (step >= 0) {
    extra = way_.drift_rate * static_cast<double>(step) * dt_;
    if (way_.spike_every > 0 && step % way_.spike_every < way_.spike_steps)
      extra += way_.spike_delay;
  }
  const std::int64_t release = std::max(
      arrival_ns + static_cast<std::int64_t>(std::llround((delay + extra) * 1e9)), last_release_);
  last_release_ = release;
  last_delay_ = std::max(0.0, static_cast<double>(release - arrival_ns) * 1e-9 - extra);
  return release;
}

bool LinkWayLag::active() const {
  return way_.one_way_delay > 0 || way_.jitter > 0 || way_.loss > 0 || way_.drift_rate > 0 ||
         (way_.spike_delay > 0 && way_.spike_every > 0) || way_.drop_steps > 0;
}

std::vector<std::int64_t> link_answer_steps(const LinkModel& link, double dt, std::size_t steps) {
  if (!(dt > 0)) throw std::invalid_argument("link_answer_steps: dt must be > 0 s");
  LinkWayLag to_node(link.to_node, dt), from_node(link.from_node, dt);
  std::vector<std::int64_t> used(steps, 0);
  std::vector<std::optional<std::int64_t>> arrival(steps);
  for (std::size_t k = 1; k < steps; ++k) {
    const auto step = static_cast<std::int64_t>(k);
    const std::int64_t sent = std::llround(static_cast<double>(k) * dt * 1e9);
    const std::optional<std::int64_t> at_lab = to_node.release(sent, step);
    if (at_lab) arrival[k] = from_node.release(*at_lab, step);
  }
  // Both ways are FIFO, so the answers that arrive do so in step order: one sweep finds, for
  // each step, the newest answer in by its time.
  std::size_t next = 1;
  std::int64_t newest = 0;
  for (std::size_t k = 1; k < steps; ++k) {
    const std::int64_t now = std::llround(static_cast<double>(k) * dt * 1e9);
    for (; next <= k; ++next) {
      if (!arrival[next]) continue;
      if (*arrival[next] > now) break;
      newest = static_cast<std::int64_t>(next);
    }
    used[k] = newest;
  }
  return used;
}

double nominal_round_trip(const LinkModel& link) {
  return link.to_node.one_way_delay + link.from_node.one_way_delay;
}

namespace {

// The terms of one way that are on: "30 ms, jitter 2.5 ms, loss 1 %, drift 0.1 ms/s".
std::string describe_way(const LinkWay& way) {
  std::ostringstream text;
  text << format_ms(way.one_way_delay);
  if (way.jitter > 0) text << ", jitter " << format_ms(way.jitter);
  if (way.loss > 0) text << ", loss " << 100.0 * way.loss << " %";
  if (way.drift_rate > 0) text << ", drift " << 1e3 * way.drift_rate << " ms/s";
  if (way.spike_every > 0 && way.spike_steps > 0)
    text << ", spikes " << format_ms(way.spike_delay) << " " << way.spike_steps << " of every "
         << way.spike_every << " steps";
  if (way.drop_steps > 0)
    text << ", steps " << way.drop_first_step << ".." << way.drop_first_step + way.drop_steps - 1
         << " dropped";
  return text.str();
}

}  // namespace

std::string describe_link(const LinkModel& link) {
  const std::string to = describe_way(link.to_node), from = describe_way(link.from_node);
  if (to == from) return "link " + to + " each way";
  return "link to " + to + " / from " + from;
}

AnswerSchedule link_schedule(const std::vector<LinkModel>& links, double dt, std::size_t steps) {
  AnswerSchedule schedule;
  for (const LinkModel& link : links)
    schedule.actuator_used.push_back(link_answer_steps(link, dt, steps));
  return schedule;
}

LinkAnswerStats link_answer_stats(const std::vector<std::int64_t>& used) {
  LinkAnswerStats stats;
  std::vector<std::int64_t> ages;
  std::int64_t previous = 0;
  for (std::size_t k = 1; k < used.size(); ++k) {
    if (used[k] == 0) continue;
    const std::int64_t age = static_cast<std::int64_t>(k) - used[k];
    ages.push_back(age);
    stats.max_age = std::max(stats.max_age, age);
    if (used[k] != previous) ++stats.used_answers;
    if (previous > 0 && used[k] == previous) ++stats.repeated_steps;
    if (previous > 0 && used[k] > previous + 1)
      stats.unused_answers += static_cast<std::size_t>(used[k] - previous - 1);
    previous = used[k];
  }
  if (!ages.empty()) {
    const auto middle = ages.begin() + static_cast<std::ptrdiff_t>(ages.size() / 2);
    std::nth_element(ages.begin(), middle, ages.end());
    stats.median_age = *middle;
  }
  return stats;
}

}  // namespace rths::core
