#pragma once
// A node's set-up of its part (NodeService::build_part), as it goes. A large model (thousands of
// DOFs) takes seconds to read, check and split, and the node answers nothing meanwhile; past its
// quiet time (util::ProgressPace: 3 s, then at most one line every 5 s) a line names the node,
// the phase it is in and the time so far, e.g.
//   "node 1 (substructure): setting up its part: reading and checking the study's structure;
//    3.1 s so far"
// and, once any line was printed, one when the part is built: "... part set up in 7.4 s".
// A line is asked for at each phase's start (phase()) and, after watch(), by a thread of its own
// every `period_s` seconds while a phase lasts (a phase is one call: nothing inside it reports).
// The lines go to `print` (a node's log: spdlog info). phase(), poll() and finish() may be called
// from any thread.

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "util/progress_pace.h"

namespace rths::runtime {

class SetupProgress {
 public:
  using Print = std::function<void(const std::string&)>;

  // The set-up of the node named `label` starts now.
  SetupProgress(std::string label, util::ProgressPacing pacing, Print print);
  // Stops and joins the watcher; prints nothing.
  ~SetupProgress();
  SetupProgress(const SetupProgress&) = delete;
  SetupProgress& operator=(const SetupProgress&) = delete;

  // The phase starting now: what the node does ("reading and checking the study's structure").
  void phase(std::string what);
  // A line, if one is due now.
  void poll();
  // Polls every `period_s` (> 0) seconds of steady_clock on a thread of its own until finish()
  // or destruction.
  void watch(double period_s);
  // The part is built: stops the watcher, asks for a line on the last phase, then says how long
  // the set-up took if it said anything before (a short set-up prints nothing at all).
  void finish();

 private:
  void stop_watch();

  const std::string label_;
  const Print print_;
  std::mutex mutex_;  // guards pace_, phase_, stopping_
  std::condition_variable wake_;
  util::ProgressPace pace_;
  std::string phase_ = "starting";
  bool stopping_ = false;
  std::thread watcher_;
};

}  // namespace rths::runtime
