#pragma once
// A lab's real-time controller written from docs/controller.md alone (not from
// controller_node/ or controller_emulator/): what a lab would put on its target to test rths's
// CONTROLLER node from the other end of the wire. It runs on its own threads in the test process
// and speaks UDP on 127.0.0.1.
//
// Its frames differ from the shipped dry run's on purpose (every field ORDER_BIG, SI scaled to mm
// and kN, PADDING in both frames, STATUS I32 in both):
//   command  (20 bytes): counter U32 | spare PADDING U32 | status I32 | target F32 mm |
//                        spare2 PADDING F32
//   feedback (24 bytes): counter U32 (echo) | status I32 | spare PADDING U32 |
//                        displacement F32 mm | force F32 kN | spare2 PADDING F32
// It writes 0xDEADBEEF into its feedback's U32 padding and `f32_padding` (a quiet NaN by default)
// into the F32 one: the docs say padding is never read ("a float field NaN or infinite (padding is
// never read)"), so a node that judged it would hold.
//
// Its plant, one step per command frame (each frame is one step of the host, dt apart): the
// measured displacement follows the target with a pure lag of round(pure_lag / dt) frames, or a
// first-order lag (tau dx/dt = target - x, exact per frame), or none; the measured force is
// stiffness x measured displacement (a linear specimen).
//
// Answers: each leaves answer_lag after its own frame arrived, whatever else is in flight (a
// sender thread releases a FIFO of answers at their due times; frames keep being received and
// stepped meanwhile), never one at a time.
//
// Statuses (docs/controller.md "What the controller must do on each status"):
//   0 run   follow the target; answer status 0.
//   1 hold  hold the frame's target (the position the node last measured): the plant jumps its
//           state to it (a lag-free hold; the docs' ramp is the rig's business); answer status 0
//           ("still settling") until held_after_hold_frames HOLD frames came, status 1 (held)
//           from then on; < 0: never says held (a controller that cannot).
//   2 stop  the rig's own stop: answers nothing to it or to anything after it.
//
// Faults, switched on at the command frame whose counter is fault_frame (and every run frame
// after it): they corrupt the answers to run frames only; HOLD frames keep being answered
// truthfully, except kSilent, which answers nothing at all from then on (a pulled cable).
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace rths::test {

enum class DocFault {
  kNone,
  kSilent,             // answers nothing (not even HOLD frames)
  kBadStatus,          // status fault_value (an interlock's code)
  kNanForce,           // force NaN
  kWrongEcho,          // echo = counter + 100000 (a counter never sent)
  kWrongSize,          // the feedback frame 4 bytes longer
  kOutOfRange,         // measured displacement fault_value m
  kCounterReset,       // echo restarts at 1 (counters already answered)
  kReboot,             // state lost once: displacement and force back to 0, echo still correct
  kForceJump,          // force + fault_value N from then on
  kStuckDisplacement,  // measured displacement frozen at its value before the fault
};
std::string to_string(DocFault fault);

struct DocControllerOptions {
  int port = 0;                  // the controller's UDP port (the link's peer_port)
  int node_port = 0;             // where answers go (the link's local_port)
  double dt = 0.001;             // s between command frames (the host's step)
  double stiffness = 0.0;        // N/m, the linear specimen
  double pure_lag = 0.0;         // s, rounded to whole frames
  double first_order_tau = 0.0;  // s; > 0 replaces the pure lag
  double answer_lag = 0.0;       // s after each frame's arrival
  int held_after_hold_frames = 3;
  DocFault fault = DocFault::kNone;
  std::uint32_t fault_frame = 0;
  double fault_value = 0.0;
  float f32_padding = std::numeric_limits<float>::quiet_NaN();  // the feedback's F32 PADDING
};

// One command frame as it arrived.
struct ReceivedFrame {
  std::uint32_t counter = 0;
  std::int32_t status = 0;
  double target = 0.0;  // m (decoded from mm)
  std::size_t bytes = 0;
  bool padding_zero = true;     // both padding fields were written 0
  std::int64_t receive_ns = 0;  // CLOCK_MONOTONIC
};

// One answer as it left.
struct SentAnswer {
  std::uint32_t counter = 0;  // of the frame it answers
  std::uint32_t echo = 0;     // as sent
  std::int32_t status = 0;
  double displacement = 0.0;  // m, as sent (after the f32 rounding)
  double force = 0.0;         // N, as sent (after the f32 rounding)
  bool faulty = false;        // a fault shaped it
  std::int64_t send_ns = 0;   // CLOCK_MONOTONIC
};

// The frames above as ControllerLink text for a study (127.0.0.1, the given ports); `extra` is
// appended inside the link (reply_timeout_ms, max_force_rate...).
std::string doc_controller_link_text(int node_port, int peer_port, const std::string& extra = "");

inline constexpr double kMm = 0.001;   // scale of a field in mm
inline constexpr double kKn = 1000.0;  // scale of a field in kN
inline constexpr std::size_t kDocCommandBytes = 20;
inline constexpr std::size_t kDocFeedbackBytes = 24;

// Quantises a value as it crosses one F32 field at `scale` (SI -> frame -> SI).
double through_f32(double si, double scale);

class DocController {
 public:
  // Binds 127.0.0.1:options.port before returning (a frame sent before would be lost).
  explicit DocController(const DocControllerOptions& options);
  ~DocController();
  DocController(const DocController&) = delete;
  DocController& operator=(const DocController&) = delete;

  // Stops the threads; received() and sent() stay readable.
  void stop();

  std::vector<ReceivedFrame> received() const;
  std::vector<SentAnswer> sent() const;

 private:
  struct Pending {
    std::int64_t due_ns;
    std::vector<std::uint8_t> bytes;
    SentAnswer answer;
  };
  void receive_loop();
  void send_loop();
  // Steps the plant for one arrived frame; false when nothing is to be answered.
  bool answer_for(const ReceivedFrame& frame, SentAnswer& answer, std::vector<std::uint8_t>& out);
  void send_now(Pending& pending);

  DocControllerOptions options_;
  int socket_ = -1;
  std::atomic<bool> running_{true};
  std::thread receiver_, sender_;

  mutable std::mutex log_mutex_;
  std::vector<ReceivedFrame> received_;
  std::vector<SentAnswer> sent_;

  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<Pending> queue_;

  // Plant state (receiver thread only).
  std::deque<double> history_;  // targets of the last lag frames, oldest first
  double measured_ = 0.0;
  bool stopped_ = false;
  bool silent_ = false;
  bool rebooted_ = false;
  bool stuck_ = false;
  double stuck_at_ = 0.0;
  int hold_frames_ = 0;
};

}  // namespace rths::test
