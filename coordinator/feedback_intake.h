#pragma once
// FeedbackIntake: the coordinator's side of the nodes' FEEDBACK messages, between the thread that
// receives them and the integrator loop that uses them.
//
//   producer  offer(message) on whichever thread receives (the transport's receive thread through
//             its inline handler, or the loop itself on a transport without one). It judges the
//             message as the loop would: envelope (run id, known node), step order against the
//             newest commanded step (await_step), payload size. An accepted message is decoded
//             straight into the node's LatestBox slot (no allocation once warm) and published.
//             Returns true when it completed the awaited step: every awaited node has now
//             answered it, so the waiting loop should be woken (one wake-up per step, not one
//             per answer). A node not awaited (a real-time link slower than the loop's wait)
//             never completes a step.
//   consumer  take(node) on the loop thread: wait-free; the node's newest feedback, if new since
//             the last take. latest(node) reads the last taken one without copying it.
// Answers: the first FEEDBACK of a step is the node's answer to it (counted, its lag measured).
// A later one for the same step with a newer servo_sample (an emulator streaming its servo loop)
// replaces the measurement but is not a new answer; anything else older is rejected. Newest wins
// in the box, so a loop that takes once per step still sees every answer count and the lag of
// the newest answer (they travel in the value).
// Rejected messages are counted per cause (rejected(), once the producer has stopped).
// Producers are serialised by a mutex the consumer never takes.

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "runtime/latest_box.h"
#include "runtime/validation.h"
#include "transport/transport.h"

namespace rths::coordinator {

// One node's newest feedback, as the loop reads it.
struct ArrivedFeedback {
  runtime::Feedback feedback;       // the newest accepted measurement (answer or servo sample)
  std::int64_t answered_step = 0;   // step of the newest answer; 0 before the first
  std::uint64_t answers = 0;        // answers accepted so far
  runtime::LinkSample link;         // the newest answer's lag (s); answered_step 0 before one
};

struct IntakeNode {
  int id = 0;
  int values = 0;         // forces per feedback (the node's storeys or actuators)
  bool emulator = false;  // also sends realised drifts, as many
  bool awaited = true;    // the loop waits for its answer to each step (see offer())
};

class FeedbackIntake {
 public:
  FeedbackIntake(std::string run_id, const std::vector<IntakeNode>& nodes);

  // Loop: the newest step commanded so far (before its commands are sent); answers to later
  // steps are out of order.
  void await_step(std::int64_t step) { awaited_.store(step, std::memory_order_release); }

  // Producer. @pre message.kind == FEEDBACK. True when this answer completed the awaited step.
  bool offer(const transport::Message& message);

  // Consumer (one thread). nullptr when nothing new arrived since the last take.
  const ArrivedFeedback* take(int node_id) { return box(node_id).try_get(); }
  const ArrivedFeedback& latest(int node_id) { return box(node_id).latest(); }

  runtime::RejectCounters rejected() const;

 private:
  struct Node {
    IntakeNode shape;
    // Producer's own view (under producer_mutex_).
    std::int64_t last_answer = 0, servo_sample = 0;
    std::uint64_t answers = 0;
    runtime::LinkSample link;
    runtime::LatestBox<ArrivedFeedback> box;
  };
  runtime::LatestBox<ArrivedFeedback>& box(int node_id) { return nodes_.at(node_id)->box; }

  const std::string run_id_;
  std::map<int, std::unique_ptr<Node>> nodes_;  // fixed after construction
  std::atomic<std::int64_t> awaited_{0};
  mutable std::mutex producer_mutex_;
  runtime::RejectCounters rejected_;
};

}  // namespace rths::coordinator
