#pragma once
// One command frame to a lab's real-time controller and its answer, judged. State: the frame
// counter, the counters of the frames it never got an answer to, and the link report (runtime::
// ControllerReport: frames by cause, round trips).
//
// Input of exchange(): the step's command in SI (time s, drifts m, drift velocities m/s), one
// entry per actuator the node hosts. It stamps the next counter (1, 2, ...), status RUN (0),
// sends the frame and waits up to the reply timeout for the feedback frame that echoes it.
// Output: kAnswered with the measured drifts (m) and forces (N) and the round trip (s), kLate (real
// time: no answer in time, the step goes unanswered), or kFault with the reason.
//
// Every datagram while it waits is judged in this order; nothing rejected is ever applied:
//   not from the configured peer (address and port)  -> wrong_source, named; waits on (an
//                                                       outsider cannot stop the run)
//   from the peer, size != the feedback frame's       -> wrong_size          -> kFault
//   a float field NaN or infinite                      -> non_finite          -> kFault
//   counter of a frame that went unanswered (real time) -> late; waits on
//   counter already answered, or older                 -> repeated_counter    -> kFault
//   counter never sent                                 -> unexpected_counter  -> kFault
//   STATUS field not 0 (the controller is not running) -> bad_status          -> kFault
//   |measured drift| > max_drift or |force| > max_force -> out_of_range       -> kFault
//   (limits <= 0: not checked)
// No answer within the timeout: lost. Lockstep -> kFault at once (a lockstep step cannot go on
// without it); real time -> kLate, and `lost_window` lost in a row -> kFault.
// send_status(1 = hold, 2 = stop): a frame with the next counter, the status, and the newest
// targets (so a controller that ignores STATUS still sees no jump).

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "controller_node/frame.h"
#include "controller_node/udp_link.h"
#include "rths/proto/runtime.pb.h"

namespace rths::controller_node {

inline constexpr std::int64_t kStatusRun = 0, kStatusHold = 1, kStatusStop = 2;

struct ExchangeSettings {
  int actuators = 0;
  double reply_timeout = 1.0;  // s
  bool real_time = false;
  int lost_window = 1;     // real time: lost answers in a row before kFault
  double max_drift = 0.0;  // m; <= 0: not checked
  double max_force = 0.0;  // N; <= 0: not checked
};

class ControllerExchange {
 public:
  enum class Outcome { kAnswered, kLate, kFault };
  struct Answer {
    Outcome outcome = Outcome::kFault;
    std::vector<double> displacement, force;  // m, N; kAnswered only
    double round_trip = 0.0;                  // s
    std::int64_t status = 0;
    std::string fault;  // kFault: why
  };

  // Throws std::invalid_argument naming the field for a bad layout, std::runtime_error when the
  // socket cannot be bound.
  ControllerExchange(const config::ControllerLink& link, const ExchangeSettings& settings);

  Answer exchange(double time, const std::vector<double>& drift,
                  const std::vector<double>& velocity);
  bool send_status(std::int64_t status);
  const runtime::ControllerReport& report() const { return report_; }
  std::string peer() const { return link_->peer(); }

 private:
  // kAnswered, kFault, or kLate meaning "not this one, wait on".
  Answer judge(const Datagram& d, std::int64_t sent_ns);
  Answer judge_counter(const std::string& from);
  enum class Cause {
    kWrongSource,
    kWrongSize,
    kNonFinite,
    kLate,
    kRepeated,
    kUnexpected,
    kBadStatus,
    kOutOfRange
  };
  void reject(Cause cause, const std::string& why);
  bool send_frame(std::int64_t status);
  config::ControllerLink config_;
  ExchangeSettings settings_;
  std::unique_ptr<UdpLink> link_;
  FrameValues out_, in_;
  std::vector<std::uint8_t> bytes_;
  std::int64_t counter_ = 0;
  std::deque<std::int64_t> unanswered_;  // newest lost counters (at most kKeepLost)
  static constexpr std::size_t kKeepLost = 256;
  int lost_in_a_row_ = 0;
  runtime::ControllerReport report_;
};

}  // namespace rths::controller_node
