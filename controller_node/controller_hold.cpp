// The hold of ControllerExchange (controller_exchange.h states the contract): HOLD frames at the
// position where the rig is, ended only by the rig's own answer to one of them, every frame of it
// logged.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "controller_node/controller_exchange.h"

namespace rths::controller_node {
namespace {

std::int64_t ns_of(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

}  // namespace

void ControllerExchange::begin_hold(std::int64_t now_ns) {
  if (holding_) return;
  holding_ = true;
  hold_started_ns_ = now_ns;
  // The position to hold, not moving: where a restarted rig measured itself; else where the
  // specimen was last measured; else the newest target.
  if (restart_measured_)
    std::copy(restart_position_.begin(), restart_position_.end(), out_.target_displacement.begin());
  else if (measured_)
    std::copy(last_displacement_.begin(), last_displacement_.end(),
              out_.target_displacement.begin());
  std::fill(out_.target_velocity.begin(), out_.target_velocity.end(), 0.0);
  next_hold_frame_ns_ = now_ns;
  first_hold_counter_ = counter_ + 1;
  hold_step(now_ns);
}

bool ControllerExchange::hold_step(std::int64_t now_ns) {
  if (!holding_) return true;
  while (link_->try_receive(datagram_)) judge(datagram_);
  const bool done = held_ || now_ns - hold_started_ns_ >= ns_of(settings_.hold_time);
  if (done || now_ns < next_hold_frame_ns_) return done;
  send_frame(kStatusHold, -1);
  report_.set_hold_frames(report_.hold_frames() + 1);
  log_hold(runtime::HoldEntry::SENT_HOLD, now_ns, counter_, kStatusHold, out_.target_displacement,
           nullptr, "");
  // Every dt at first; past kHoldBurst frames every kHoldSpacing dt, so a controller that
  // stalled wakes to a short backlog with the STOP behind it, not a buffer full of HOLDs. The
  // next frame is due a period after this one left, never earlier: a late wake-up sends one
  // frame, not the ones it missed.
  const std::int64_t period = std::max<std::int64_t>(ns_of(settings_.dt), 100000);
  next_hold_frame_ns_ =
      now_ns + (report_.hold_frames() < kHoldBurst ? period : kHoldSpacing * period);
  return false;
}

bool ControllerExchange::send_stop() {
  const bool sent = send_frame(kStatusStop, -1);
  log_hold(runtime::HoldEntry::SENT_STOP, clock_->now_ns(), counter_, kStatusStop,
           out_.target_displacement, nullptr, sent ? "" : send_fault_);
  return sent;
}

// "" when the decoded answer echoes a HOLD frame that left before the answer arrived and was not
// answered before; else why it cannot end the hold.
std::string ControllerExchange::hold_echo_problem(std::int64_t received_ns) const {
  const std::int64_t c = in_.counter;
  if (c <= 0 || c > counter_)
    return fmt::format("echoes frame {}, never sent (newest {})", c, counter_);
  const InFlight& f = in_flight_[static_cast<std::size_t>(c) % kInFlight];
  if (f.counter != c || c < first_hold_counter_)
    return fmt::format("echoes frame {}, a frame sent before the hold (the first HOLD frame is {})",
                       c, first_hold_counter_);
  if (f.status != kStatusHold) return fmt::format("echoes frame {}, not a HOLD frame", c);
  if (received_ns < f.sent_ns) return fmt::format("answers HOLD frame {} before it left", c);
  if (f.state == InFlight::State::kAnswered)
    return fmt::format("repeats the answer to HOLD frame {}", c);
  return {};
}

void ControllerExchange::reject_hold_answer(const std::string& why) {
  report_.set_hold_rejected(report_.hold_rejected() + 1);
  report_.set_last_hold_reject(why);
  if (report_.hold_rejected() <= 20 || report_.hold_rejected() % 1000 == 0)
    spdlog::warn("controller {}: while holding, an answer that does not end the hold: {}",
                 link_->peer(), why);
}

// An answer while holding: only a status-HOLD echo of a HOLD frame sent before it arrived ends
// the hold. After a restart the hold follows the position the rig answers with.
void ControllerExchange::judge_hold_answer(const Datagram& d) {
  const FrameVerdict verdict =
      decode(config_.feedback(), d.bytes.data(), d.size, settings_.actuators, in_);
  if (verdict != FrameVerdict::kOk) {
    const std::string why =
        "a frame of " + std::to_string(d.size) + " bytes: " + to_string(verdict);
    log_hold(runtime::HoldEntry::ANSWER, d.received_ns, 0, 0, out_.target_displacement, nullptr,
             why);
    reject_hold_answer(why);
    return;
  }
  std::string why = hold_echo_problem(d.received_ns);
  if (why.empty() && !restarted_epoch().empty()) {
    restarted_ = true;
    report_.set_restart(fmt::format("the controller restarted while held: epoch {}", in_.epoch));
  }
  const bool ends = why.empty() && in_.has_status && in_.status == kStatusHold;
  log_hold(runtime::HoldEntry::ANSWER, d.received_ns, in_.counter, in_.status,
           in_.measured_displacement, &in_.measured_force,
           !why.empty() ? why
           : ends       ? "held"
                        : "holding");
  if (!why.empty()) {
    reject_hold_answer(why);
    return;
  }
  slot(in_.counter).state = InFlight::State::kAnswered;
  report_.set_last_status(static_cast<std::int32_t>(in_.status));
  bool within = true;
  for (const double x : in_.measured_displacement)
    within = within && std::isfinite(x) &&
             !(settings_.max_drift > 0 && std::abs(x) > settings_.max_drift);
  if (restarted_ && within)
    std::copy(in_.measured_displacement.begin(), in_.measured_displacement.end(),
              out_.target_displacement.begin());
  if (!ends || held_) return;
  held_ = true;
  report_.set_held_after(static_cast<double>(d.received_ns - hold_started_ns_) * 1e-9);
  spdlog::info(
      "controller {}: reports held {:.3f} ms after the first HOLD frame (its answer to "
      "HOLD frame {})",
      link_->peer(), report_.held_after() * 1e3, in_.counter);
}

void ControllerExchange::log_hold(runtime::HoldEntry::Kind kind, std::int64_t now_ns,
                                  std::int64_t counter, std::int64_t status,
                                  const std::vector<double>& position,
                                  const std::vector<double>* force, const std::string& verdict) {
  if (report_.hold_log_size() >= kHoldLog) {
    report_.set_hold_log_dropped(report_.hold_log_dropped() + 1);
    return;
  }
  runtime::HoldEntry* e = report_.add_hold_log();
  e->set_kind(kind);
  e->set_time(static_cast<double>(now_ns - hold_started_ns_) * 1e-9);
  e->set_counter(counter);
  e->set_status(status);
  for (const double x : position) e->add_position(x);
  if (force)
    for (const double f : *force) e->add_force(f);
  e->set_verdict(verdict);
}

}  // namespace rths::controller_node
