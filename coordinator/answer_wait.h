#pragma once
// AnswerWait: whether a real-time step waits for one node's answer, judged from how long its
// answers take. Waiting for an answer pays only while it comes within the wait; one that cannot
// (the machine's round trip is longer than the wait, as at 4096 Hz on a loopback across CPUs)
// eats the wait out of every period and turns small hiccups into overruns, and the step goes on
// with the newest answer anyway.
//   input   step(round_trip): each new answer's round trip r (s, coordinator clock: answer
//           received - command sent), on the loop thread.
//   state   the last kJudged round trips (a ring), whether the node is waited for, and how many
//           answers since the last switch (or the start).
//   rule    every kJudged answers, on the last kJudged: waiting and median(r) > wait -> stop
//           waiting; not waiting and median(r) < wait / 4 -> wait again. The gap is wide because
//           waiting itself lengthens the round trip (by more than half at 4096 Hz on this project's
//           VM: README), so a narrow one switches back and forth.
//           The first judgement comes after kJudged answers, the one after the first switch
//           after kSettle, and each later one after twice as many as the one before: a run
//           switches a handful of times at most.
//   output  a Switch (the new state and the median that decided it) when the state changed.
// Allocation-free: fixed-size ring, the median on a stack copy.

#include <array>
#include <cstddef>
#include <optional>

namespace rths::coordinator {

class AnswerWait {
 public:
  static constexpr std::size_t kJudged = 64;    // answers per judgement
  static constexpr std::size_t kSettle = 1024;  // answers after the first switch before the next

  struct Switch {
    bool waiting = true;
    double median_round_trip = 0.0;  // s, of the kJudged answers that decided it
  };

  explicit AnswerWait(double wait) : wait_(wait) {}  // wait: s, the step's wait for answers

  std::optional<Switch> step(double round_trip);
  bool waiting() const { return waiting_; }

 private:
  double wait_;
  std::array<double, kJudged> ring_{};
  std::size_t next_ = 0, since_switch_ = 0;
  std::size_t settle_ = kJudged;  // answers before the next judgement may switch
  bool waiting_ = true;
};

}  // namespace rths::coordinator
