#include "controller_node/controller_exchange.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/time_text.h"

namespace rths::controller_node {
namespace {

constexpr std::uint64_t kLoggedRejects = 20;  // then every 1000th, so a flood cannot fill a log
// A configured limit is named as set (%g, 6 significant digits); a measured time to 3 (format_ms).
constexpr int kSettingDigits = 6;

std::int64_t ns_of(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

// The default clock of every exchange: CLOCK_MONOTONIC (stateless, so one serves all).
runtime::PacingClock& monotonic_clock() {
  static runtime::MonotonicClock clock;
  return clock;
}

void check_setting(double value, const char* field) {
  if (!std::isfinite(value) || value < 0)
    throw std::invalid_argument(std::string("controller.") + field + " must be finite and >= 0");
}

}  // namespace

ControllerExchange::ControllerExchange(const config::ControllerLink& link,
                                       const ExchangeSettings& settings,
                                       std::unique_ptr<DatagramLink> datagrams,
                                       runtime::PacingClock* clock)
    : config_(link), settings_(settings), clock_(clock ? clock : &monotonic_clock()) {
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
  speeds_.assign(kInFlight * n, 0.0);
  restart_position_.assign(n, 0.0);
  diagnostic_fields_ = diagnostic_fields(link.feedback());
  in_.diagnostics.assign(diagnostic_fields_.size(), 0.0);
  round_trips_.reserve(kRoundTrips);
  sorted_.reserve(kRoundTrips);
  bytes_.reserve(frame_size(link.command()));
  report_.set_held_after(-1.0);
  report_.mutable_diagnostics()->Resize(static_cast<int>(diagnostic_fields_.size()), 0.0);
  link_ = datagrams ? std::move(datagrams)
                    : std::make_unique<UdpLink>(link.local_address(), link.local_port(),
                                                link.peer_address(), link.peer_port());
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
  frame = InFlight{counter_, step, clock_->now_ns(), status, out_.time, InFlight::State::kPending};
  ++pending_;
  const auto at = static_cast<std::ptrdiff_t>((static_cast<std::size_t>(counter_) % kInFlight) *
                                              out_.target_displacement.size());
  std::copy(out_.target_displacement.begin(), out_.target_displacement.end(),
            targets_.begin() + at);
  std::transform(out_.target_velocity.begin(), out_.target_velocity.end(), speeds_.begin() + at,
                 [](double v) { return std::abs(v); });
  if (!encode(config_.command(), out_, bytes_)) {
    send_fault_ = "frame " + std::to_string(counter_) + " carries a value its layout cannot hold";
    return false;
  }
  report_.set_frames_sent(report_.frames_sent() + 1);
  if (status != kStatusRun) settle(frame, InFlight::State::kLost);  // status frames await nothing
  const int error = link_->send(bytes_.data(), bytes_.size());
  if (error == 0 || icmp_errno(error))
    return true;  // an ICMP error: counted, the frame may be lost
  send_fault_ = "cannot send frame " + std::to_string(counter_) + " to " + link_->peer() + ": " +
                std::strerror(error) + " (errno " + std::to_string(error) + ")";
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
ControllerExchange::Answer ControllerExchange::judge_counter(InFlight*& frame,
                                                             std::int64_t received_ns) {
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
    const double round_trip = static_cast<double>(received_ns - f.sent_ns) * 1e-9;
    late(f, round_trip,
         from() + " answers frame " + std::to_string(c) + " (step " + std::to_string(f.step) +
             ") late, after " + core::format_ms(round_trip) +
             (c < newest_answered_ ? " (a newer frame was answered first)" : ""));
    return a;  // kNone: ignored
  }
  frame = &f;
  a.outcome = Outcome::kAnswered;
  return a;
}

// The peak |target velocity| of actuator `k` over the kSpeedWindow frames up to `counter`.
double ControllerExchange::peak_speed(std::int64_t counter, int k) const {
  double peak = 0.0;
  const auto n = static_cast<std::size_t>(settings_.actuators);
  for (std::int64_t c = std::max<std::int64_t>(1, counter - kSpeedWindow + 1); c <= counter; ++c)
    peak = std::max(
        peak, speeds_[(static_cast<std::size_t>(c) % kInFlight) * n + static_cast<std::size_t>(k)]);
  return peak;
}

std::string ControllerExchange::jump(const InFlight& frame, std::int64_t received_ns, int i) const {
  const auto k = static_cast<std::size_t>(i);
  const double moved = in_.measured_displacement[k] - last_displacement_[k];
  const double span =
      std::max({frame.time - last_time_,
                static_cast<double>(received_ns - last_received_ns_) * 1e-9, settings_.dt});
  const double speed = peak_speed(frame.counter, i);
  const double bound = 2.0 * speed * span + settings_.jump_floor;
  if (std::abs(moved) <= bound) return {};
  return fmt::format(
      "implausible measurement: the measured drift of actuator {} (frame {}, step {}) jumped "
      "{:.3f} mm in {:.3f} ms, beyond 2 x the peak target velocity {:.4f} m/s x {:.3f} ms + "
      "jump_floor {:.3f} mm = {:.3f} mm (a restarted controller or a sensor fault)",
      i + 1, frame.counter, frame.step, moved * 1e3, span * 1e3, speed, span * 1e3,
      settings_.jump_floor * 1e3, bound * 1e3);
}

// The tracking check of actuator `i`: "" within its bound; `off` set when beyond it.
std::string ControllerExchange::tracking(const InFlight& frame, int i, bool& off) const {
  const auto k = static_cast<std::size_t>(i);
  const double x = in_.measured_displacement[k], target = targets_of(frame.counter)[k];
  double bound = settings_.max_tracking_error;
  const bool adaptive = !(bound > 0) && settings_.tracking_lag > 0;
  if (adaptive)
    bound = 2.0 * peak_speed(frame.counter, i) * settings_.tracking_lag +
            std::max(settings_.jump_floor, 0.0) + 1e-3;
  if (!(bound > 0) || std::abs(x - target) <= bound) return {};
  off = true;
  if (tracking_streak_ + 1 < settings_.tracking_error_steps) return {};
  return fmt::format(
      "tracking error: actuator {} (frame {}, step {}) measured {:.3f} mm for a target of {:.3f} "
      "mm (|error| {:.3f} mm beyond {} {:.3f} mm for {} answers in a row)",
      i + 1, frame.counter, frame.step, x * 1e3, target * 1e3, std::abs(x - target) * 1e3,
      adaptive ? "the tracking bound (2 x peak target velocity x expected lag + floor)"
               : "max_tracking_error",
      bound * 1e3, tracking_streak_ + 1);
}

std::string ControllerExchange::implausible(const InFlight& frame, std::int64_t received_ns,
                                            bool& jumped) {
  const double span = measured_ ? frame.time - last_time_ : 0.0;
  const double dt = span > 0 ? span : settings_.dt;
  bool tracking_off = false;
  for (int i = 0; i < settings_.actuators; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double x = in_.measured_displacement[k], f = in_.measured_force[k];
    if (measured_ && settings_.max_measured_rate > 0 && dt > 0) {
      const double rate = std::abs(x - last_displacement_[k]) / dt;
      jumped = rate > settings_.max_measured_rate;
      if (jumped)
        return fmt::format(
            "implausible measurement: the measured drift of actuator {} (frame {}, step {}) "
            "moved {:.3f} mm in {:.3f} ms ({:.3f} m/s, bound max_measured_rate {:.3f} m/s)",
            i + 1, frame.counter, frame.step, (x - last_displacement_[k]) * 1e3, dt * 1e3, rate,
            settings_.max_measured_rate);
    }
    if (measured_ && settings_.jump_floor > 0)
      if (std::string why = jump(frame, received_ns, i); !why.empty()) {
        jumped = true;
        return why;
      }
    if (measured_ && settings_.max_force_rate > 0 && dt > 0) {
      const double rate = std::abs(f - last_force_[k]) / dt;
      if (rate > settings_.max_force_rate)
        return fmt::format(
            "implausible measurement: the measured force of actuator {} (frame {}, step {}) "
            "moved {:.1f} N in {:.3f} ms ({:.1f} N/s, bound max_force_rate {:.1f} N/s)",
            i + 1, frame.counter, frame.step, f - last_force_[k], dt * 1e3, rate,
            settings_.max_force_rate);
    }
    if (std::string why = tracking(frame, i, tracking_off); !why.empty()) return why;
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
  for (std::size_t i = 0; i < diagnostic_fields_.size(); ++i) {
    const FrameField& f = diagnostic_fields_[i];
    const double v = in_.diagnostics[i];
    if (f.min() < f.max() && (v < f.min() || v > f.max()))
      return fmt::format("a diagnostic {} of {:g}{}, outside its bounds [{:g}, {:g}]", f.name(), v,
                         f.unit().empty() ? "" : " (SI; frame unit " + f.unit() + ")", f.min(),
                         f.max());
  }
  return {};
}

ControllerExchange::Answer ControllerExchange::judge(const Datagram& d) {
  if (!d.from_peer) {
    reject(Cause::kWrongSource, "frame from " + source_text(d) + " (not the controller " +
                                    link_->peer() + "), " + std::to_string(d.size) + " bytes");
    return Answer{};
  }
  if (holding_) {
    judge_hold_answer(d);
    return Answer{};
  }
  return judge_decoded(d);
}

// The datagram decoded into in_, or the fault that it cannot be (wrong size, not finite).
ControllerExchange::Answer ControllerExchange::decode_answer(const Datagram& d) {
  Answer a;
  const FrameVerdict verdict =
      decode(config_.feedback(), d.bytes.data(), d.size, settings_.actuators, in_);
  if (verdict == FrameVerdict::kOk) {
    a.outcome = Outcome::kAnswered;
    return a;
  }
  a.outcome = Outcome::kFault;
  const std::string from = "frame from " + source_text(d);
  if (verdict == FrameVerdict::kWrongSize) {
    a.fault = from + " has " + std::to_string(d.size) + " bytes, the feedback frame " +
              std::to_string(frame_size(config_.feedback()));
    reject(Cause::kWrongSize, a.fault);
    return a;
  }
  a.fault = from + " carries a value that is not finite";
  if (in_.non_finite_field >= 0) {
    const FrameField& f = config_.feedback().fields(in_.non_finite_field);
    a.fault += " in field " + std::to_string(in_.non_finite_field) + " (" +
               (f.name().empty() ? FrameField::Role_Name(f.role()) : f.name()) + ", " +
               FrameField::Role_Name(f.role()) + ")";
  }
  reject(Cause::kNonFinite, a.fault);
  return a;
}

// A frame from the peer while running, judged in the order controller_exchange.h states.
ControllerExchange::Answer ControllerExchange::judge_decoded(const Datagram& d) {
  if (Answer decoded = decode_answer(d); decoded.outcome != Outcome::kAnswered) return decoded;
  Answer a;
  a.outcome = Outcome::kFault;
  // Texts are built only on the way to a rejection: an accepted frame allocates nothing.
  const auto from = [&d] { return "frame from " + source_text(d); };
  if (std::string why = restarted_epoch(); !why.empty()) {
    note_restart(why);
    a.fault = std::move(why);
    reject(Cause::kImplausible, a.fault);
    return a;
  }
  InFlight* frame = nullptr;
  if (Answer counter = judge_counter(frame, d.received_ns); counter.outcome != Outcome::kAnswered)
    return counter;
  const double round_trip = static_cast<double>(d.received_ns - frame->sent_ns) * 1e-9;
  if (round_trip > settings_.reply_timeout) {
    late(*frame, round_trip,
         from() + " answers frame " + std::to_string(frame->counter) + " (step " +
             std::to_string(frame->step) + ") after " + core::format_ms(round_trip) +
             " (reply timeout " + core::format_ms(settings_.reply_timeout, kSettingDigits) + ")");
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
  bool jumped = false;
  if (std::string why = implausible(*frame, d.received_ns, jumped); !why.empty()) {
    if (jumped) note_restart(why);
    a.fault = std::move(why);
    reject(Cause::kImplausible, a.fault);
    return a;
  }
  accept(*frame, round_trip, d.received_ns);
  a.outcome = Outcome::kAnswered;
  a.step = frame->step;
  a.displacement = &in_.measured_displacement;
  a.force = &in_.measured_force;
  a.diagnostics = &in_.diagnostics;
  a.status = in_.status;
  a.round_trip = round_trip;
  return a;
}

// "" unless the frame's CONTROLLER_EPOCH differs from the one the controller answered with so far.
std::string ControllerExchange::restarted_epoch() {
  if (!in_.has_epoch) return {};
  const bool changed = epoch_seen_ && in_.epoch != epoch_;
  const std::int64_t before = epoch_;
  epoch_ = in_.epoch;
  epoch_seen_ = true;
  if (!changed) return {};
  return fmt::format("the controller {} restarted: its epoch went from {} to {} (frame {})",
                     link_->peer(), before, in_.epoch, in_.counter);
}

// The decoded answer echoes a frame still awaited: its measurement is the rig's, now.
bool ControllerExchange::echoes_frame_in_flight() const {
  const std::int64_t c = in_.counter;
  if (c <= 0 || c > counter_) return false;
  const InFlight& f = in_flight_[static_cast<std::size_t>(c) % kInFlight];
  return f.counter == c && f.state == InFlight::State::kPending;
}

// A restart: the hold must hold where the restarted rig is. Its measurement is taken only from an
// answer to a frame in flight (not a replay of an old one) and within the run's drift limit.
void ControllerExchange::note_restart(const std::string& why) {
  restarted_ = true;
  report_.set_restart(why);
  bool usable = echoes_frame_in_flight();
  for (const double x : in_.measured_displacement)
    usable = usable && std::isfinite(x) &&
             !(settings_.max_drift > 0 && std::abs(x) > settings_.max_drift);
  if (!usable) return;
  std::copy(in_.measured_displacement.begin(), in_.measured_displacement.end(),
            restart_position_.begin());
  restart_measured_ = true;
}

void ControllerExchange::late(InFlight& frame, double round_trip, const std::string& why) {
  settle(frame, InFlight::State::kLost);
  report_.set_round_trip_max(std::max(report_.round_trip_max(), round_trip));
  locate(*report_.mutable_late_frames(), frame, round_trip);
  ++late_since_accept_;
  newest_late_ = why;
  reject(Cause::kLate, why);
}

void ControllerExchange::locate(google::protobuf::RepeatedPtrField<runtime::FrameMiss>& list,
                                const InFlight& frame, double round_trip) {
  if (list.size() >= kLocated) return;
  runtime::FrameMiss* miss = list.Add();
  miss->set_counter(frame.counter);
  miss->set_step(frame.step);
  miss->set_round_trip(round_trip);
}

void ControllerExchange::accept(const InFlight& frame, double round_trip,
                                std::int64_t received_ns) {
  settle(slot(frame.counter), InFlight::State::kAnswered);
  newest_answered_ = frame.counter;
  lost_in_a_row_ = 0;
  late_since_accept_ = 0;
  last_received_ns_ = received_ns;
  for (int i = 0; i < report_.diagnostics_size(); ++i)
    report_.set_diagnostics(i, in_.diagnostics[static_cast<std::size_t>(i)]);
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
    locate(*report_.mutable_lost_frames(), f, 0.0);
    ++lost_in_a_row_;
    const std::string why = silence(f);
    report_.set_last_reject(why);
    if (!settings_.real_time || lost_in_a_row_ >= settings_.lost_window) {
      a.outcome = Outcome::kFault;
      a.fault = why + " (" + std::to_string(lost_in_a_row_) + " lost in a row)";
      return a;
    }
  }
  return a;
}

// Why frame `f` went unanswered: the controller answers late (it falls behind), or is silent.
std::string ControllerExchange::silence(const InFlight& f) const {
  const std::string frame =
      "frame " + std::to_string(f.counter) + " (step " + std::to_string(f.step) + ")";
  if (late_since_accept_ > 0)
    return "the controller " + link_->peer() + " answers late: " + frame + " unanswered within " +
           core::format_ms(settings_.reply_timeout, kSettingDigits) + ", and " +
           std::to_string(late_since_accept_) +
           " answers since the newest applied one came after their reply timeout (newest: " +
           newest_late_ + ")";
  return "the controller " + link_->peer() + " did not answer " + frame + " within " +
         core::format_ms(settings_.reply_timeout, kSettingDigits);
}

ControllerExchange::Answer ControllerExchange::next(std::int64_t now_ns) {
  while (link_->try_receive(datagram_)) {
    Answer a = judge(datagram_);
    if (a.outcome != Outcome::kNone) return a;
  }
  if (holding_) return Answer{};
  return expire(now_ns);
}

const runtime::ControllerReport& ControllerExchange::report() {
  report_.set_icmp_errors(link_->icmp_errors());
  if (link_->icmp_errors() > 0)
    report_.set_last_icmp_error(fmt::format(
        "{} (errno {})", std::strerror(link_->last_icmp_errno()), link_->last_icmp_errno()));
  report_.set_drained_before_connect(link_->drained_before_connect());
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
