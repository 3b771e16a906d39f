#pragma once
// FeedbackIntake: the coordinator's side of the nodes' FEEDBACK messages, between the thread that
// receives them and the integrator loop that uses them.
//
//   producer  offer(message) on whichever thread receives (the transport's receive thread through
//             its inline handler, or the loop itself on a transport without one). It judges the
//             message as the loop would: envelope (run id, known node), sender (the node's own
//             topic and, once pinned, its own writer), step order against the newest commanded
//             step (await_step) and, for that step, the echo of the node's command (command_sent:
//             nothing for a step is accepted before its command left), payload size, and values
//             (forces, realised drifts finite, realised within max_displacement when set; lag and
//             stamps finite and not negative). An accepted message is decoded straight into the
//             node's LatestBox slot (no allocation once warm) and published.
//             Returns true when it completed the awaited step (every awaited node has now
//             answered it, so the waiting loop should be woken: one wake-up per step, not one
//             per answer) or raised an integrity fault. A node not awaited (a real-time link
//             slower than the loop's wait) never completes a step.
//   consumer  take(node) on the loop thread: wait-free; the node's newest feedback, if new since
//             the last take. latest(node) reads the last taken one without copying it.
//             fault() (wait-free): the integrity fault, once one was raised.
// Answers: the first FEEDBACK of a step is the node's answer to it (counted, its lag measured).
// A later one for the same step with a newer servo_sample (an emulator streaming its servo loop)
// replaces the measurement but is not a new answer; the same bytes again are a duplicate;
// anything else older is rejected. Newest wins in the box, so a loop that takes once per step
// still sees every answer count and the lag of the newest answer (they travel in the value).
// Integrity faults (the run must stop: someone else speaks as the node, or the node contradicts
// itself), raised once, naming the node and both arrivals:
//   an answer as node N from another writer than N's pinned one (pin(), from its announcement);
//   two different answers to the same step (and servo sample) from node N.
// Rejected messages are counted per cause (rejected(), once the producer has stopped).
// Producers are serialised by a mutex the consumer never takes.

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "runtime/node/validation.h"
#include "runtime/rt/latest_box.h"
#include "transport/transport.h"

namespace rths::coordinator {

// One node's newest feedback, as the loop reads it.
struct ArrivedFeedback {
  runtime::Feedback feedback;      // the newest accepted measurement (answer or servo sample)
  std::int64_t answered_step = 0;  // step of the newest answer; 0 before the first
  std::uint64_t answers = 0;       // answers accepted so far
  runtime::LinkSample link;        // the newest answer's lag (s); answered_step 0 before one
};

struct IntakeNode {
  int id = 0;
  int values = 0;         // forces per feedback (the node's storeys or actuators)
  bool emulator = false;  // also sends realised drifts, as many
  bool awaited = true;    // the loop waits for its answer to each step (see offer()), at the
                          // start (set_awaited changes it)
};

// The run's integrity fault: which node, and what (both arrivals, with their stamps).
struct IntegrityFault {
  int node_id = 0;
  std::string what;
};

class FeedbackIntake {
 public:
  // max_realised: m, |realised drift| allowed (0: finite only).
  FeedbackIntake(std::string run_id, const std::vector<IntakeNode>& nodes,
                 double max_realised = 0.0);

  // Loop: the newest step commanded so far (before its commands are sent); answers to later
  // steps are out of order.
  void await_step(std::int64_t step) { awaited_.store(step, std::memory_order_release); }
  // Loop, after await_step and before node_id's command of that step leaves: the command's
  // sent_ns, which every answer to the awaited step must echo.
  void command_sent(int node_id, std::int64_t sent_ns) {
    nodes_.at(node_id)->command_echo.store(sent_ns, std::memory_order_release);
  }
  // Loop: whether the loop waits for the node's answers from now on (starts as its shape's).
  void set_awaited(int node_id, bool awaited) {
    nodes_.at(node_id)->awaited.store(awaited, std::memory_order_release);
  }
  // The writer the node's announcement came from (0: none known); before the run starts.
  void pin(int node_id, std::uint64_t writer);

  // Producer. @pre message.kind == FEEDBACK. True when this answer completed the awaited step.
  bool offer(const transport::Message& message);

  // Consumer (one thread). nullptr when nothing new arrived since the last take.
  const ArrivedFeedback* take(int node_id) { return box(node_id).try_get(); }
  const ArrivedFeedback& latest(int node_id) { return box(node_id).latest(); }

  runtime::RejectCounters rejected() const;
  // Loop: nullptr until an integrity fault was raised; then the fault (never changes again).
  const IntegrityFault* fault() const {
    return faulted_.load(std::memory_order_acquire) ? &fault_ : nullptr;
  }

 private:
  // One accepted answer as the conflict check remembers it.
  struct Arrival {
    std::uint64_t payload_hash = 0, writer = 0;
    std::int64_t sent_ns = 0, received_ns = 0;
  };
  struct Node {
    IntakeNode shape;
    std::atomic<bool> awaited{true};             // shape.awaited, then as the loop sets it
    std::atomic<std::int64_t> command_echo{-1};  // -1: no command sent yet
    // Producer's own view (under producer_mutex_).
    std::uint64_t writer = 0;  // pinned; 0 = not checked
    std::int64_t last_answer = 0, servo_sample = 0;
    std::uint64_t answers = 0;
    Arrival accepted;  // the newest accepted answer or servo sample
    runtime::LinkSample link;
    runtime::LatestBox<ArrivedFeedback> box;
  };
  runtime::LatestBox<ArrivedFeedback>& box(int node_id) { return nodes_.at(node_id)->box; }
  // The envelope, sender and step order; kAccept or why not. Raises a fault for another writer.
  runtime::Verdict judge(const transport::Message& message, Node*& node);
  // Whether the answer to the awaited step echoes its command (see the acquire order inside).
  bool echoes_command(const transport::Message& message, Node& node) const;
  bool values_in_range(const runtime::Feedback& feedback) const;
  // Same step as the node's newest answer: a newer servo sample (kAccept), the same bytes
  // (kDuplicate), or a contradiction (raises the fault, kDuplicate).
  runtime::Verdict judge_repeat(const transport::Message& message, Node& node, std::uint64_t hash,
                                std::int64_t servo_sample);
  void raise(int node_id, std::string what);
  void record_answer(const transport::Message& message, Node& node, std::uint64_t hash);

  const std::string run_id_;
  const double max_realised_;
  std::map<int, std::unique_ptr<Node>> nodes_;  // fixed after construction
  std::atomic<std::int64_t> awaited_{0};
  std::atomic<bool> faulted_{false};
  IntegrityFault fault_;  // written once, before faulted_ is set
  mutable std::mutex producer_mutex_;
  runtime::RejectCounters rejected_;
};

}  // namespace rths::coordinator
