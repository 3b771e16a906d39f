#include "controller_node/controller_exchange.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rths::controller_node {
namespace {

constexpr std::uint64_t kLoggedRejects = 20;  // then every 1000th, so a flood cannot fill a log

std::string ms(double seconds) { return std::to_string(seconds * 1e3) + " ms"; }

std::int64_t ns_of(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

void check_setting(double value, const char* field) {
  if (!std::isfinite(value) || value < 0)
    throw std::invalid_argument(std::string("controller.") + field + " must be finite and >= 0");
}

}  // namespace

ControllerExchange::ControllerExchange(const config::ControllerLink& link,
                                       const ExchangeSettings& settings)
    : config_(link), settings_(settings) {
  runtime::check_frame_layout(link.command(), settings.actuators, Direction::kCommand,
                              "controller.command");
  runtime::check_frame_layout(link.feedback(), settings.actuators, Direction::kFeedback,
                              "controller.feedback");
  for (const auto* layout : {&link.command(), &link.feedback()})
    if (frame_size(*layout) > kMaxDatagram)
      throw std::invalid_argument("controller: a frame of " + std::to_string(frame_size(*layout)) +
                                  " bytes (at most " + std::to_string(kMaxDatagram) + ")");
  if (!(settings.reply_timeout > 0) || !std::isfinite(settings.reply_timeout))
    throw std::invalid_argument("controller.reply_timeout_ms must be > 0 and finite");
  check_setting(settings.max_measured_rate, "max_measured_rate");
  check_setting(settings.max_force_rate, "max_force_rate");
  check_setting(settings.max_tracking_error, "max_tracking_error");
  check_setting(settings.hold_time, "hold_time_ms");
  const auto n = static_cast<std::size_t>(settings.actuators);
  for (auto* v : {&out_.target_displacement, &out_.target_velocity, &out_.measured_displacement,
                  &out_.measured_force, &last_displacement_, &last_force_})
    v->assign(n, 0.0);
  in_flight_.assign(kInFlight, InFlight{});
  targets_.assign(kInFlight * n, 0.0);
  round_trips_.reserve(kRoundTrips);
  sorted_.reserve(kRoundTrips);
  bytes_.reserve(frame_size(link.command()));
  report_.set_held_after(-1.0);
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
    case Cause::kImplausible: r.set_implausible(r.implausible() + 1); break;
    default: r.set_out_of_range(r.out_of_range() + 1);
  }
  report_.set_last_reject(why);
  const std::uint64_t n = r.wrong_source() + r.wrong_size() + r.repeated_counter() +
                          r.unexpected_counter() + r.non_finite() + r.out_of_range() +
                          r.bad_status() + r.late() + r.implausible();
  if (n <= kLoggedRejects || n % 1000 == 0)
    spdlog::warn("controller {}: rejected: {} ({} rejected so far)", link_->peer(), why, n);
}

bool ControllerExchange::send_frame(std::int64_t status, std::int64_t step) {
  out_.counter = ++counter_;
  out_.status = status;
  InFlight& frame = slot(counter_);
  if (frame.state == InFlight::State::kPending) {
    // Overwritten before its timeout (more than kInFlight frames within it): lost.
    settle(frame, InFlight::State::kLost);
    report_.set_lost(report_.lost() + 1);
  }
  frame = InFlight{counter_, step, monotonic_ns(), out_.time, InFlight::State::kPending};
  ++pending_;
  std::copy(out_.target_displacement.begin(), out_.target_displacement.end(),
            targets_.begin() +
                static_cast<std::ptrdiff_t>((static_cast<std::size_t>(counter_) % kInFlight) *
                                            out_.target_displacement.size()));
  if (!encode(config_.command(), out_, bytes_)) {
    send_fault_ = "frame " + std::to_string(counter_) + " carries a value its layout cannot hold";
    return false;
  }
  report_.set_frames_sent(report_.frames_sent() + 1);
  if (status != kStatusRun) settle(frame, InFlight::State::kLost);  // status frames await nothing
  if (link_->send(bytes_.data(), bytes_.size())) return true;
  send_fault_ = "cannot send frame " + std::to_string(counter_) + " to " + link_->peer();
  return false;
}

bool ControllerExchange::send_command(std::int64_t step, double time,
                                      const std::vector<double>& drift,
                                      const std::vector<double>& velocity) {
  out_.time = time;
  std::copy(drift.begin(), drift.end(), out_.target_displacement.begin());
  std::copy(velocity.begin(), velocity.end(), out_.target_velocity.begin());
  const bool sent = send_frame(kStatusRun, step);
  report_.set_in_flight(pending_);
  return sent;
}

void ControllerExchange::settle(InFlight& frame, InFlight::State state) {
  if (frame.state == InFlight::State::kPending) --pending_;
  frame.state = state;
}

// The datagram's counter against the frames in flight.
ControllerExchange::Answer ControllerExchange::judge_counter(InFlight*& frame) {
  Answer a;
  const std::int64_t c = in_.counter;
  // Texts are built only on the way to a rejection: an accepted frame allocates nothing.
  const auto from = [this] { return "frame from " + link_->peer(); };
  if (c > counter_ || c <= 0) {
    a.outcome = Outcome::kFault;
    a.fault = from() + " echoes counter " + std::to_string(c) + ", never sent (newest " +
              std::to_string(counter_) + ")";
    reject(Cause::kUnexpected, a.fault);
    return a;
  }
  InFlight& f = slot(c);
  // An echo of a frame answered already, or older than any frame the ring holds (long answered
  // or lost: no late answer comes kInFlight frames after its own): the controller repeats
  // itself, or its counter was reset (a reboot).
  if (f.counter != c || f.state == InFlight::State::kAnswered) {
    a.outcome = Outcome::kFault;
    a.fault = from() + " repeats counter " + std::to_string(c) +
              (f.counter != c
                   ? " (older than every frame in flight; newest " + std::to_string(counter_) + ")"
                   : " (already answered)");
    reject(Cause::kRepeated, a.fault);
    return a;
  }
  // The answer to a frame already lost, or overtaken by a newer answer: late, never applied.
  if (f.state == InFlight::State::kLost || c < newest_answered_) {
    settle(f, InFlight::State::kLost);
    reject(Cause::kLate, from() + " answers frame " + std::to_string(c) + " late");
    return a;  // kNone: ignored
  }
  frame = &f;
  a.outcome = Outcome::kAnswered;
  return a;
}

std::string ControllerExchange::implausible(const InFlight& frame) {
  const double span = measured_ ? frame.time - last_time_ : 0.0;
  const double dt = span > 0 ? span : settings_.dt;
  const double* target = targets_of(frame.counter);
  bool tracking_off = false;
  for (int i = 0; i < settings_.actuators; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double x = in_.measured_displacement[k], f = in_.measured_force[k];
    const auto who = [&] {
      return "actuator " + std::to_string(i + 1) + " (frame " + std::to_string(frame.counter) +
             ", step " + std::to_string(frame.step) + ")";
    };
    if (measured_ && settings_.max_measured_rate > 0 && dt > 0) {
      const double rate = std::abs(x - last_displacement_[k]) / dt;
      if (rate > settings_.max_measured_rate)
        return "implausible measurement: the measured drift of " + who() + " moved " +
               std::to_string((x - last_displacement_[k]) * 1e3) + " mm in " + ms(dt) + " (" +
               std::to_string(rate) + " m/s, bound max_measured_rate " +
               std::to_string(settings_.max_measured_rate) + " m/s)";
    }
    if (measured_ && settings_.max_force_rate > 0 && dt > 0) {
      const double rate = std::abs(f - last_force_[k]) / dt;
      if (rate > settings_.max_force_rate)
        return "implausible measurement: the measured force of " + who() + " moved " +
               std::to_string(f - last_force_[k]) + " N in " + ms(dt) + " (" +
               std::to_string(rate) + " N/s, bound max_force_rate " +
               std::to_string(settings_.max_force_rate) + " N/s)";
    }
    if (settings_.max_tracking_error > 0 &&
        std::abs(x - target[k]) > settings_.max_tracking_error) {
      tracking_off = true;
      if (tracking_streak_ + 1 >= settings_.tracking_error_steps)
        return "tracking error: " + who() + " measured " + std::to_string(x * 1e3) +
               " mm for a target of " + std::to_string(target[k] * 1e3) + " mm (|error| " +
               std::to_string(std::abs(x - target[k]) * 1e3) + " mm beyond max_tracking_error " +
               std::to_string(settings_.max_tracking_error * 1e3) + " mm for " +
               std::to_string(tracking_streak_ + 1) + " answers in a row)";
    }
  }
  tracking_streak_ = tracking_off ? tracking_streak_ + 1 : 0;
  return {};
}

// "" when every measurement is within the run's limits, else the first one beyond, named.
std::string ControllerExchange::out_of_range() const {
  for (int i = 0; i < settings_.actuators; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double x = in_.measured_displacement[k], f = in_.measured_force[k];
    if (settings_.max_drift > 0 && std::abs(x) > settings_.max_drift)
      return "a drift of " + std::to_string(x) + " m on actuator " + std::to_string(i + 1) +
             ", beyond the run's limit of " + std::to_string(settings_.max_drift) +
             " m (twice limits.max_displacement)";
    if (settings_.max_force > 0 && std::abs(f) > settings_.max_force)
      return "a force of " + std::to_string(f) + " N on actuator " + std::to_string(i + 1) +
             ", beyond controller.max_force " + std::to_string(settings_.max_force) + " N";
  }
  return {};
}

void ControllerExchange::note_hold_answer(const Datagram& d) {
  if (decode(config_.feedback(), d.bytes.data(), d.size, settings_.actuators, in_) !=
      FrameVerdict::kOk)
    return;
  if (!in_.has_status || in_.status != kStatusHold || held_) return;
  held_ = true;
  report_.set_last_status(static_cast<std::int32_t>(in_.status));
  report_.set_held_after(static_cast<double>(d.received_ns - hold_started_ns_) * 1e-9);
  spdlog::info("controller {}: reports held {:.3f} ms after the first HOLD frame", link_->peer(),
               report_.held_after() * 1e3);
}

ControllerExchange::Answer ControllerExchange::judge(const Datagram& d) {
  Answer a;
  // Texts are built only on the way to a rejection: an accepted frame allocates nothing.
  const auto from = [&d] { return "frame from " + source_text(d); };
  if (!d.from_peer) {
    reject(Cause::kWrongSource, from() + " (not the controller " + link_->peer() + "), " +
                                    std::to_string(d.size) + " bytes");
    return a;
  }
  if (holding_) {
    note_hold_answer(d);
    return a;
  }
  const FrameVerdict verdict =
      decode(config_.feedback(), d.bytes.data(), d.size, settings_.actuators, in_);
  a.outcome = Outcome::kFault;
  if (verdict == FrameVerdict::kWrongSize) {
    a.fault = from() + " has " + std::to_string(d.size) + " bytes, the feedback frame " +
              std::to_string(frame_size(config_.feedback()));
    reject(Cause::kWrongSize, a.fault);
    return a;
  }
  if (verdict == FrameVerdict::kNonFinite) {
    a.fault = from() + " carries a value that is not finite";
    if (in_.non_finite_field >= 0) {
      const config::FrameField& f = config_.feedback().fields(in_.non_finite_field);
      a.fault += " in field " + std::to_string(in_.non_finite_field) + " (" +
                 (f.name().empty() ? config::FrameField::Role_Name(f.role()) : f.name()) + ", " +
                 config::FrameField::Role_Name(f.role()) + ")";
    }
    reject(Cause::kNonFinite, a.fault);
    return a;
  }
  InFlight* frame = nullptr;
  if (Answer counter = judge_counter(frame); counter.outcome != Outcome::kAnswered) return counter;
  const double round_trip = static_cast<double>(d.received_ns - frame->sent_ns) * 1e-9;
  if (round_trip > settings_.reply_timeout) {
    settle(*frame, InFlight::State::kLost);
    reject(Cause::kLate, from() + " answers frame " + std::to_string(frame->counter) + " after " +
                             ms(round_trip) + " (reply timeout " + ms(settings_.reply_timeout) +
                             ")");
    return Answer{};
  }
  report_.set_last_status(static_cast<std::int32_t>(in_.status));
  if (in_.has_status && in_.status != kStatusRun) {
    a.fault = "the controller reports status " + std::to_string(in_.status) + " (not running)";
    reject(Cause::kBadStatus, a.fault);
    return a;
  }
  if (std::string why = out_of_range(); !why.empty()) {
    a.fault = from() + " (counter " + std::to_string(frame->counter) + ") measures " + why;
    reject(Cause::kOutOfRange, a.fault);
    return a;
  }
  if (std::string why = implausible(*frame); !why.empty()) {
    a.fault = std::move(why);
    reject(Cause::kImplausible, a.fault);
    return a;
  }
  accept(*frame, round_trip);
  a.outcome = Outcome::kAnswered;
  a.step = frame->step;
  a.displacement = &in_.measured_displacement;
  a.force = &in_.measured_force;
  a.status = in_.status;
  a.round_trip = round_trip;
  return a;
}

void ControllerExchange::accept(const InFlight& frame, double round_trip) {
  settle(slot(frame.counter), InFlight::State::kAnswered);
  newest_answered_ = frame.counter;
  lost_in_a_row_ = 0;
  std::copy(in_.measured_displacement.begin(), in_.measured_displacement.end(),
            last_displacement_.begin());
  std::copy(in_.measured_force.begin(), in_.measured_force.end(), last_force_.begin());
  last_time_ = frame.time;
  measured_ = true;
  report_.set_frames_accepted(report_.frames_accepted() + 1);
  report_.set_round_trip_last(round_trip);
  report_.set_round_trip_max(std::max(report_.round_trip_max(), round_trip));
  if (round_trips_.size() < kRoundTrips)
    round_trips_.push_back(round_trip);
  else
    round_trips_[round_trip_next_] = round_trip;
  round_trip_next_ = (round_trip_next_ + 1) % kRoundTrips;
}

// Frames past their reply timeout: lost. Frames leave in counter order, so the walk starts at the
// oldest frame that may still be pending and stops at the first pending one still in time.
ControllerExchange::Answer ControllerExchange::expire(std::int64_t now_ns) {
  Answer a;
  const std::int64_t timeout = ns_of(settings_.reply_timeout);
  oldest_pending_ = std::max(oldest_pending_, counter_ - static_cast<std::int64_t>(kInFlight) + 1);
  for (; oldest_pending_ <= counter_; ++oldest_pending_) {
    InFlight& f = slot(oldest_pending_);
    if (f.counter != oldest_pending_ || f.state != InFlight::State::kPending) continue;
    if (now_ns - f.sent_ns <= timeout) break;
    settle(f, InFlight::State::kLost);
    report_.set_lost(report_.lost() + 1);
    ++lost_in_a_row_;
    const std::string silent = "the controller " + link_->peer() + " did not answer frame " +
                               std::to_string(f.counter) + " (step " + std::to_string(f.step) +
                               ") within " + ms(settings_.reply_timeout);
    report_.set_last_reject(silent);
    if (!settings_.real_time || lost_in_a_row_ >= settings_.lost_window) {
      a.outcome = Outcome::kFault;
      a.fault = silent + " (" + std::to_string(lost_in_a_row_) + " lost in a row)";
      return a;
    }
  }
  return a;
}

ControllerExchange::Answer ControllerExchange::next(std::int64_t now_ns) {
  while (link_->try_receive(datagram_)) {
    Answer a = judge(datagram_);
    if (a.outcome != Outcome::kNone) return a;
  }
  if (holding_) return Answer{};
  return expire(now_ns);
}

void ControllerExchange::begin_hold(std::int64_t now_ns) {
  if (holding_) return;
  holding_ = true;
  hold_started_ns_ = now_ns;
  // The position to hold: where the specimen was last measured (the newest target before any
  // measurement); not moving.
  if (measured_)
    std::copy(last_displacement_.begin(), last_displacement_.end(),
              out_.target_displacement.begin());
  std::fill(out_.target_velocity.begin(), out_.target_velocity.end(), 0.0);
  next_hold_frame_ns_ = now_ns;
  hold_step(now_ns);
}

bool ControllerExchange::hold_step(std::int64_t now_ns) {
  if (!holding_) return true;
  while (link_->try_receive(datagram_)) judge(datagram_);
  const bool done = held_ || now_ns - hold_started_ns_ >= ns_of(settings_.hold_time);
  if (done || now_ns < next_hold_frame_ns_) return done;
  send_frame(kStatusHold, -1);
  report_.set_hold_frames(report_.hold_frames() + 1);
  // Every dt at first; past kHoldBurst frames every kHoldSpacing dt, so a controller that
  // stalled wakes to a short backlog with the STOP behind it, not a buffer full of HOLDs.
  const std::int64_t period = std::max<std::int64_t>(ns_of(settings_.dt), 100000);
  next_hold_frame_ns_ =
      now_ns + (report_.hold_frames() < kHoldBurst ? period : kHoldSpacing * period);
  return false;
}

bool ControllerExchange::send_stop() { return send_frame(kStatusStop, -1); }

const runtime::ControllerReport& ControllerExchange::report() {
  if (!round_trips_.empty()) {
    sorted_.assign(round_trips_.begin(), round_trips_.end());
    const auto at = [this](double q) {
      const auto k = static_cast<std::size_t>(q * static_cast<double>(sorted_.size() - 1));
      std::nth_element(sorted_.begin(), sorted_.begin() + static_cast<std::ptrdiff_t>(k),
                       sorted_.end());
      return sorted_[k];
    };
    report_.set_round_trip_median(at(0.5));
    report_.set_round_trip_p99(at(0.99));
  }
  return report_;
}

}  // namespace rths::controller_node
