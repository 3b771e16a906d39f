#pragma once
// The frames to and from a lab's real-time controller, judged, with several frames in flight.
// Nothing waits here: a command frame leaves when send_command() is called, answers are judged
// as next() reads them, and a frame unanswered for the reply timeout counts lost (a staleness
// limit, never a blocking wait).
//
// State: the frame counter; the frames in flight (a fixed ring of kInFlight: counter, the step
// it commands, its send time and targets); the newest accepted measurement (for the rate
// checks); the hold (position, frames, held); the link report (runtime::ControllerReport).
//
// send_command(step, time s, drift m, velocity m/s) -> stamps the next counter (1, 2, ...),
//   status RUN (0), sends it. False when it cannot be encoded or sent (fault() says why).
// next(now_ns) -> the next accepted answer (kAnswered: the step its frame commanded, the
//   measured drifts m and forces N, the frame's round trip s), a fault (kFault, named), or kNone
//   once nothing is queued. Every datagram is judged in this order; nothing rejected is applied:
//   not from the configured peer (only a spoofed or pre-connect one reaches here) -> wrong_source,
//                                                        counted, named, ignored
//   from the peer, size != the feedback frame's          -> wrong_size          -> kFault
//   a float field NaN or infinite (padding never read)    -> non_finite          -> kFault
//   counter never sent                                    -> unexpected_counter  -> kFault
//   counter already answered, or older than the ring holds (a reset counter, a reboot)
//                                                         -> repeated_counter    -> kFault
//   counter of a frame past its reply timeout, or older than the newest answered one
//                                                         -> late; ignored
//   holding: status HOLD (1) -> held; anything else ignored (the rig is being held)
//   STATUS field not 0 (the controller is not running)   -> bad_status          -> kFault
//   |measured drift| > max_drift or |force| > max_force   -> out_of_range        -> kFault
//   |d measured drift| / d t > max_measured_rate, |d force| / d t > max_force_rate (d t: between
//   the two answered frames' command times), or |measured - target drift| > max_tracking_error
//   for tracking_error_steps answers in a row            -> implausible         -> kFault
//   (every limit <= 0: not checked)
//   measured jump (on by default: jump_floor > 0): |d measured drift| between two answered
//   frames > 2 x the peak |target velocity| of the kSpeedWindow frames up to the answered one x
//   the longer of the frames' command span, the answers' arrival span and dt, + jump_floor
//                                                         -> implausible (a restart)  -> kFault
//   tracking, adaptive (max_tracking_error 0, tracking_lag > 0): the bound is 2 x that peak
//   velocity x tracking_lag + jump_floor + 1 mm          -> implausible              -> kFault
//   a CONTROLLER_EPOCH field that changed                 -> restarted (a restart)    -> kFault
//   a DIAGNOSTIC field outside its [min, max] (min < max) -> out_of_range             -> kFault
//   Then frames sent more than the reply timeout ago are lost: lockstep -> kFault at once (the
//   step cannot go on without its answer); real time -> lost_window lost in a row -> kFault, named
//   "late" when answers to frames since the newest accepted one came after their timeout.
//   Lost and late frames are located (counter, step) in the report, the first kLocated of each.
// A restart (a measured drift beyond max_measured_rate or the jump bound, a changed epoch, on an
//   answer echoing a frame in flight): its measured drifts are where the rebooted rig is; the
//   hold holds there, never at a position measured before the restart, and then follows what the
//   rig answers to the HOLD frames (so a single glitched sample is held for one frame at most).
// The hold: begin_hold(now) sends a HOLD frame (status 1) carrying the position to hold (the
//   restarted rig's measurement, else the newest accepted measured drift, else the newest
//   target) and hold_step(now) repeats it every dt, never faster (the first kHoldBurst, then every
//   kHoldSpacing dt: a stalled controller's buffer holds the STOP too), until the controller
//   answers with status HOLD (1) an echo of a HOLD frame sent before that answer arrived, or
//   hold_time passes; true then. Every other answer while holding (an echo of no frame, of a run
//   frame, of a HOLD frame answered already, status 1 before any HOLD frame left) is counted,
//   named (hold_rejected) and leaves the hold on. send_stop() sends the STOP frame (status 2)
//   with the same position. Every HOLD frame, answer and the STOP go to the report's hold_log.
// Threads: wait() may run on any thread (it only polls the socket); everything else on one
// thread at a time (the node serialises them). No allocation per datagram or frame once built
// (the fault texts allocate, once per fault; the hold log allocates its entries: the hold ends
// the run).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "controller_node/frame.h"
#include "controller_node/udp_link.h"
#include "rths/proto/runtime.pb.h"

namespace rths::controller_node {

using FrameField = config::FrameField;

inline constexpr std::int64_t kStatusRun = 0, kStatusHold = 1, kStatusStop = 2;

struct ExchangeSettings {
  int actuators = 0;
  double dt = 0.0;             // s, the command period: HOLD frames repeat at it
  double reply_timeout = 1.0;  // s, an unanswered frame is lost after it
  bool real_time = false;
  int lost_window = 1;              // real time: lost frames in a row before kFault
  double max_drift = 0.0;           // m
  double max_force = 0.0;           // N
  double max_measured_rate = 0.0;   // m/s
  double max_force_rate = 0.0;      // N/s
  double max_tracking_error = 0.0;  // m
  int tracking_error_steps = 3;
  double jump_floor = 0.0;    // m, the measured-jump check's floor; <= 0: not checked
  double tracking_lag = 0.0;  // s, the adaptive tracking bound's lag (max_tracking_error 0)
  double hold_time = 0.5;     // s
};

class ControllerExchange {
 public:
  static constexpr std::size_t kInFlight = 4096;  // frames judged by their counter
  static constexpr std::size_t kRoundTrips = 4096;
  static constexpr std::uint64_t kHoldBurst = 50;   // HOLD frames one dt apart, then
  static constexpr std::int64_t kHoldSpacing = 10;  // this many dt apart
  static constexpr std::int64_t kSpeedWindow = 64;  // frames whose peak target speed bounds a jump
  static constexpr int kHoldLog = 1024;             // hold_log entries kept
  static constexpr int kLocated = 64;               // lost and late frames located

  enum class Outcome { kNone, kAnswered, kFault };
  struct Answer {
    Outcome outcome = Outcome::kNone;
    std::int64_t step = 0;                              // kAnswered: the step its frame commanded
    const std::vector<double>* displacement = nullptr;  // m, valid until the next call
    const std::vector<double>* force = nullptr;         // N
    double round_trip = 0.0;                            // s
    std::int64_t status = 0;
    const std::vector<double>* diagnostics = nullptr;  // SI, the layout's DIAGNOSTIC fields
    std::string fault;                                 // kFault: why
  };

  // Throws std::invalid_argument naming the field for a bad layout or setting,
  // std::runtime_error when the socket cannot be bound or connected.
  // `datagrams`: the link to the controller; null: a UdpLink from `link`'s addresses and ports.
  // `clock`: what frames are stamped and aged on, the clock the link stamps its datagrams on and
  // waits on (it must outlive the exchange); null: CLOCK_MONOTONIC, as UdpLink's.
  ControllerExchange(const config::ControllerLink& link, const ExchangeSettings& settings,
                     std::unique_ptr<DatagramLink> datagrams = nullptr,
                     runtime::PacingClock* clock = nullptr);

  bool send_command(std::int64_t step, double time, const std::vector<double>& drift,
                    const std::vector<double>& velocity);
  Answer next(std::int64_t now_ns);
  bool wait(std::int64_t deadline_ns) const { return link_->wait(deadline_ns); }

  void begin_hold(std::int64_t now_ns);
  bool hold_step(std::int64_t now_ns);
  bool send_stop();
  bool holding() const { return holding_; }
  int actuators() const { return settings_.actuators; }
  // Now on the clock every stamp of this exchange is on (ns).
  std::int64_t now_ns() const { return clock_->now_ns(); }

  const std::string& fault() const { return send_fault_; }
  // The report with its round-trip median and p99 (sorts a preallocated copy).
  const runtime::ControllerReport& report();
  const runtime::ControllerReport& report_as_is() const { return report_; }
  std::string peer() const { return link_->peer(); }

 private:
  struct InFlight {
    std::int64_t counter = 0, step = 0, sent_ns = 0, status = 0;
    double time = 0.0;
    enum class State { kFree, kPending, kAnswered, kLost } state = State::kFree;
  };
  enum class Cause {
    kWrongSource,
    kWrongSize,
    kNonFinite,
    kLate,
    kRepeated,
    kUnexpected,
    kBadStatus,
    kOutOfRange,
    kImplausible
  };
  InFlight& slot(std::int64_t counter) {
    return in_flight_[static_cast<std::size_t>(counter) % kInFlight];
  }
  const double* targets_of(std::int64_t counter) const {
    return &targets_[(static_cast<std::size_t>(counter) % kInFlight) *
                     static_cast<std::size_t>(settings_.actuators)];
  }
  Answer judge(const Datagram& d);
  Answer judge_decoded(const Datagram& d);
  Answer decode_answer(const Datagram& d);
  // The counter's frame, or why not (a fault, or kNone meaning late: ignored).
  Answer judge_counter(InFlight*& frame, std::int64_t received_ns);
  // `jumped`: the fault is a measured drift moving faster than a rig can (max_measured_rate or
  // the jump check): a restart, or a sensor fault the answers to the HOLD frames then correct.
  std::string implausible(const InFlight& frame, std::int64_t received_ns, bool& jumped);
  std::string jump(const InFlight& frame, std::int64_t received_ns, int actuator) const;
  std::string tracking(const InFlight& frame, int actuator, bool& off) const;
  std::string restarted_epoch();
  std::string out_of_range() const;
  double peak_speed(std::int64_t counter, int actuator) const;
  bool echoes_frame_in_flight() const;
  void note_restart(const std::string& why);
  Answer expire(std::int64_t now_ns);
  std::string silence(const InFlight& frame) const;
  void locate(google::protobuf::RepeatedPtrField<runtime::FrameMiss>& list, const InFlight& frame,
              double round_trip);
  void late(InFlight& frame, double round_trip, const std::string& why);
  // The hold (controller_hold.cpp).
  void judge_hold_answer(const Datagram& d);
  std::string hold_echo_problem(std::int64_t received_ns) const;
  void reject_hold_answer(const std::string& why);
  void log_hold(runtime::HoldEntry::Kind kind, std::int64_t now_ns, std::int64_t counter,
                std::int64_t status, const std::vector<double>& position,
                const std::vector<double>* force, const std::string& verdict);
  // Leaves `state` (answered or lost) and keeps pending_ the count of kPending frames.
  void settle(InFlight& frame, InFlight::State state);
  void accept(const InFlight& frame, double round_trip, std::int64_t received_ns);
  void reject(Cause cause, const std::string& why);
  bool send_frame(std::int64_t status, std::int64_t step);

  config::ControllerLink config_;
  ExchangeSettings settings_;
  std::unique_ptr<DatagramLink> link_;
  runtime::PacingClock* clock_;
  FrameValues out_, in_;
  std::vector<std::uint8_t> bytes_;
  Datagram datagram_;
  std::vector<InFlight> in_flight_;
  std::vector<double> targets_;  // kInFlight x actuators, by counter
  std::int64_t counter_ = 0, newest_answered_ = 0;
  std::int64_t oldest_pending_ = 1;  // no frame before it is still pending
  std::uint32_t pending_ = 0;        // frames in flight (kPending)
  int lost_in_a_row_ = 0, tracking_streak_ = 0;
  // The newest accepted measurement and its frame's command time (for the rate checks).
  std::vector<double> last_displacement_, last_force_;
  double last_time_ = 0.0;
  std::int64_t last_received_ns_ = 0;
  bool measured_ = false;
  std::vector<double> speeds_;  // kInFlight x actuators: |target velocity| m/s, by counter
  std::vector<FrameField> diagnostic_fields_;
  std::int64_t epoch_ = 0;
  bool epoch_seen_ = false;
  // A restart detected: the restarted rig's measured drifts (restart_measured_: they are known).
  bool restarted_ = false, restart_measured_ = false;
  std::vector<double> restart_position_;
  // Answers judged late since the newest accepted one, and the newest such, for naming a
  // controller that falls behind.
  std::uint64_t late_since_accept_ = 0;
  std::string newest_late_;
  // The hold.
  bool holding_ = false, held_ = false;
  std::int64_t first_hold_counter_ = 0;
  std::int64_t hold_started_ns_ = 0, next_hold_frame_ns_ = 0;
  std::string send_fault_;
  std::vector<double> round_trips_, sorted_;  // ring of the newest kRoundTrips, and a scratch
  std::size_t round_trip_next_ = 0;
  runtime::ControllerReport report_;
};

}  // namespace rths::controller_node
