#pragma once
// Real-time scheduling for a run's threads. A SCHED_FIFO thread preempts every ordinary
// (SCHED_OTHER) thread of the host the moment it wakes, whatever their nice value, and is
// preempted only by real-time threads of higher priority (the kernel's own run at 99). Ordinary
// threads still get the CPU whenever the FIFO threads sleep, and the kernel's real-time
// throttling (sched_rt_runtime_us, 95 % by default) keeps a runaway FIFO thread from freezing the
// host. Without CAP_SYS_NICE (or an RLIMIT_RTPRIO at least `priority`) the kernel refuses.
// Threads the raised ones create afterwards inherit SCHED_FIFO.

#include <string>
#include <string_view>
#include <vector>

namespace rths::runtime {

// The calling thread (the loop, called `loop_name` in the summary) and this process's threads
// named in `names` on SCHED_FIFO `priority` for this object's life: the destructor puts each one
// still running back as it was, so a caller's thread (a coordinator run inside a bench, a Python
// session) is not left on SCHED_FIFO after the run. Never throws. summary() is one line for the
// run's log: "SCHED_FIFO 80: loop, dq.user, recv, recvUC" (thread-id order), or on refusal
// "SCHED_FIFO 80 refused (sched_setscheduler(loop): Operation not permitted); the threads run
// unprioritised", in which case nothing is left raised.
class FifoThreads {
 public:
  FifoThreads(int priority, std::string_view loop_name, const std::vector<std::string>& names);
  ~FifoThreads();
  FifoThreads(const FifoThreads&) = delete;
  FifoThreads& operator=(const FifoThreads&) = delete;

  const std::string& summary() const { return summary_; }
  bool raised() const { return !saved_.empty(); }

 private:
  struct Saved {
    int tid, policy, priority;  // the thread's policy and priority before it was raised
  };
  void restore();

  std::vector<Saved> saved_;
  std::string summary_;
};

// The scheduling policy of thread `tid` of this process (0: the calling thread) as ps prints it:
// "FF" SCHED_FIFO, "RR", "TS" SCHED_OTHER, "B" SCHED_BATCH, "IDL" SCHED_IDLE; "?" if unknown.
std::string scheduling_class(int tid = 0);

}  // namespace rths::runtime
