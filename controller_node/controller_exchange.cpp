#include "controller_node/controller_exchange.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rths::controller_node {
namespace {

constexpr std::uint64_t kLoggedRejects = 20;  // then every 1000th, so a flood cannot fill a log

std::string ms(double seconds) { return std::to_string(seconds * 1e3) + " ms"; }

bool beyond(const std::vector<double>& values, double limit) {
  if (!(limit > 0)) return false;
  return std::any_of(values.begin(), values.end(),
                     [limit](double x) { return std::abs(x) > limit; });
}

}  // namespace

ControllerExchange::ControllerExchange(const config::ControllerLink& link,
                                       const ExchangeSettings& settings)
    : config_(link), settings_(settings) {
  check_layout(link.command(), settings.actuators, Direction::kCommand, "controller.command");
  check_layout(link.feedback(), settings.actuators, Direction::kFeedback, "controller.feedback");
  for (const auto* layout : {&link.command(), &link.feedback()})
    if (frame_size(*layout) > kMaxDatagram)
      throw std::invalid_argument("controller: a frame of " + std::to_string(frame_size(*layout)) +
                                  " bytes (at most " + std::to_string(kMaxDatagram) + ")");
  if (!(settings.reply_timeout > 0) || !std::isfinite(settings.reply_timeout))
    throw std::invalid_argument("controller.reply_timeout_ms must be > 0");
  const auto n = static_cast<std::size_t>(settings.actuators);
  out_.target_displacement.assign(n, 0.0);
  out_.target_velocity.assign(n, 0.0);
  out_.measured_displacement.assign(n, 0.0);
  out_.measured_force.assign(n, 0.0);
  link_ = std::make_unique<UdpLink>(link.local_address(), link.local_port(), link.peer_address(),
                                    link.peer_port());
}

void ControllerExchange::reject(Cause cause, const std::string& why) {
  runtime::ControllerReport& r = report_;
  switch (cause) {
    case Cause::kWrongSource: r.set_wrong_source(r.wrong_source() + 1); break;
    case Cause::kWrongSize: r.set_wrong_size(r.wrong_size() + 1); break;
    case Cause::kNonFinite: r.set_non_finite(r.non_finite() + 1); break;
    case Cause::kLate: r.set_late(r.late() + 1); break;
    case Cause::kRepeated: r.set_repeated_counter(r.repeated_counter() + 1); break;
    case Cause::kUnexpected: r.set_unexpected_counter(r.unexpected_counter() + 1); break;
    case Cause::kBadStatus: r.set_bad_status(r.bad_status() + 1); break;
    default: r.set_out_of_range(r.out_of_range() + 1);
  }
  report_.set_last_reject(why);
  const std::uint64_t n = report_.wrong_source() + report_.wrong_size() +
                          report_.repeated_counter() + report_.unexpected_counter() +
                          report_.non_finite() + report_.out_of_range() + report_.bad_status() +
                          report_.late();
  if (n <= kLoggedRejects || n % 1000 == 0)
    spdlog::warn("controller {}: rejected: {} ({} rejected so far)", link_->peer(), why, n);
}

bool ControllerExchange::send_frame(std::int64_t status) {
  out_.counter = ++counter_;
  out_.status = status;
  if (!encode(config_.command(), out_, bytes_)) return false;
  report_.set_frames_sent(report_.frames_sent() + 1);
  return link_->send(bytes_);
}

bool ControllerExchange::send_status(std::int64_t status) { return send_frame(status); }

// The decoded frame's counter: kAnswered when it is the awaited one, kLate for the answer to a
// frame that went unanswered (counted; wait on), else kFault.
ControllerExchange::Answer ControllerExchange::judge_counter(const std::string& from) {
  Answer a;
  a.outcome = Outcome::kFault;
  const std::int64_t c = in_.counter;
  if (c < counter_) {
    const auto lost = std::find(unanswered_.begin(), unanswered_.end(), c);
    if (settings_.real_time && lost != unanswered_.end()) {
      unanswered_.erase(lost);
      reject(Cause::kLate, from + " answers frame " + std::to_string(c) + " after its timeout");
      a.outcome = Outcome::kLate;
      return a;
    }
    a.fault = from + " repeats counter " + std::to_string(c) + " (awaiting " +
              std::to_string(counter_) + ")";
    reject(Cause::kRepeated, a.fault);
    return a;
  }
  if (c > counter_) {
    a.fault = from + " echoes counter " + std::to_string(c) + ", never sent (newest " +
              std::to_string(counter_) + ")";
    reject(Cause::kUnexpected, a.fault);
    return a;
  }
  a.outcome = Outcome::kAnswered;
  return a;
}

ControllerExchange::Answer ControllerExchange::judge(const Datagram& d, std::int64_t sent_ns) {
  Answer a;
  a.outcome = Outcome::kFault;
  const std::string from = "frame from " + d.source;
  if (!d.from_peer) {
    reject(Cause::kWrongSource, from + " (not the controller " + link_->peer() + "), " +
                                    std::to_string(d.size) + " bytes");
    a.outcome = Outcome::kLate;
    return a;
  }
  const std::size_t expected = frame_size(config_.feedback());
  const FrameVerdict verdict =
      decode(config_.feedback(), d.bytes.data(), d.size, settings_.actuators, in_);
  if (verdict == FrameVerdict::kWrongSize) {
    a.fault = from + " has " + std::to_string(d.size) + " bytes, the feedback frame " +
              std::to_string(expected);
    reject(Cause::kWrongSize, a.fault);
    return a;
  }
  if (verdict == FrameVerdict::kNonFinite) {
    a.fault = from + " carries a value that is not finite";
    reject(Cause::kNonFinite, a.fault);
    return a;
  }
  if (Answer counter = judge_counter(from); counter.outcome != Outcome::kAnswered) return counter;
  const std::int64_t c = in_.counter;
  report_.set_last_status(static_cast<std::int32_t>(in_.status));
  if (in_.has_status && in_.status != kStatusRun) {
    a.fault = "the controller reports status " + std::to_string(in_.status) + " (not running)";
    reject(Cause::kBadStatus, a.fault);
    return a;
  }
  if (beyond(in_.measured_displacement, settings_.max_drift) ||
      beyond(in_.measured_force, settings_.max_force)) {
    a.fault = from + " (counter " + std::to_string(c) +
              ") measures a drift or force beyond the run's limits";
    reject(Cause::kOutOfRange, a.fault);
    return a;
  }
  a.outcome = Outcome::kAnswered;
  a.displacement = in_.measured_displacement;
  a.force = in_.measured_force;
  a.status = in_.status;
  a.round_trip = static_cast<double>(d.received_ns - sent_ns) * 1e-9;
  return a;
}

ControllerExchange::Answer ControllerExchange::exchange(double time,
                                                        const std::vector<double>& drift,
                                                        const std::vector<double>& velocity) {
  out_.time = time;
  std::copy(drift.begin(), drift.end(), out_.target_displacement.begin());
  std::copy(velocity.begin(), velocity.end(), out_.target_velocity.begin());
  Answer a;
  const std::int64_t sent_ns = monotonic_ns();  // before the send: the round trip includes it
  if (!send_frame(kStatusRun)) {
    a.fault = "cannot send command frame " + std::to_string(counter_) + " to " + link_->peer();
    return a;
  }
  const std::int64_t deadline =
      sent_ns + static_cast<std::int64_t>(std::llround(settings_.reply_timeout * 1e9));
  while (auto d = link_->receive(deadline)) {
    a = judge(*d, sent_ns);
    if (a.outcome == Outcome::kLate) continue;
    if (a.outcome == Outcome::kFault) return a;
    lost_in_a_row_ = 0;
    report_.set_frames_accepted(report_.frames_accepted() + 1);
    report_.set_round_trip_last(a.round_trip);
    report_.set_round_trip_max(std::max(report_.round_trip_max(), a.round_trip));
    return a;
  }
  report_.set_lost(report_.lost() + 1);
  ++lost_in_a_row_;
  unanswered_.push_back(counter_);
  if (unanswered_.size() > kKeepLost) unanswered_.pop_front();
  a = Answer{};
  const std::string silent = "the controller " + link_->peer() + " did not answer frame " +
                             std::to_string(counter_) + " within " + ms(settings_.reply_timeout);
  report_.set_last_reject(silent);
  if (!settings_.real_time || lost_in_a_row_ >= settings_.lost_window) {
    a.outcome = Outcome::kFault;
    a.fault = silent + " (" + std::to_string(lost_in_a_row_) + " lost in a row)";
    return a;
  }
  a.outcome = Outcome::kLate;
  return a;
}

}  // namespace rths::controller_node
