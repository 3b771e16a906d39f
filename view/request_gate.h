#pragma once
// RequestGate: the view's front door. A connection costs the server a thread only once its whole
// request is in the socket's buffer, so idle or dripping clients cannot take the threads that
// serve the page and the stop button.
//
// Inputs: accepted, connected TCP sockets (admit(), from the accepting thread); the gate owns each
// from then on and closes it.
// Outputs: `serve(fd)` called on one of `workers` threads with a socket whose request line, headers
// and body (Content-Length bytes, when it fits `max_request_bytes`) are already received (read
// with MSG_PEEK, so `serve` reads them as sent); the gate closes the socket after `serve` returns.
// Rules, each counted (counters()):
//   - a connection whose request is not complete within `header_deadline` of its arrival is
//     closed ("timed_out"): a client dripping a byte every 2 s holds nothing for long;
//   - at most `max_waiting` connections wait for their request, at most `max_per_address` of them
//     from one peer address; a new one beyond either limit displaces the waiting one idle longest
//     ("evicted"; the rule is view/admission.h's): those that have sent nothing go first, oldest
//     first, never the newest; one address at its share displaces only its own, so the slots
//     above it stay free for other hosts. Before a connection is displaced its socket is looked
//     at: one whose request has begun meanwhile is not idle (the rule is asked again), one whose
//     request is complete is served. So a client that churns connections, or holds a crowd of
//     idle ones and reopens each one closed, displaces only its own idle ones: a browser's
//     request, in its socket within a round trip of connecting, is never displaced;
//   - a request whose headers exceed `max_request_bytes` is answered 431 and closed
//     ("too_large"); one that closes before it is complete is just closed ("closed_early");
//   - at most `max_queued` complete requests wait for a worker; more are answered 503 and closed
//     ("queue_full").
// Threads: one epoll thread "view-gate" (waiting connections, deadlines at a 20 ms tick) and
// `workers` "view-serve", each on SCHED_OTHER at `nice` (enter_view_thread): on a machine the
// loop shares, a flood of requests takes CPU from the loop only where the loop leaves some, even
// when the gate is started from a thread already raised to SCHED_FIFO (whose policy new threads
// would otherwise inherit).
// Thread safety: admit() and counters() from any thread.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "view/admission.h"

namespace rths::view {

struct GateOptions {
  std::size_t max_waiting = 64;      // connections whose request is not complete yet
  std::size_t max_per_address = 56;  // of them from one peer address
  std::size_t max_queued = 64;       // complete requests waiting for a worker
  std::chrono::milliseconds header_deadline{3000};
  std::size_t max_request_bytes = 8192 + 4096;  // headers (8 KiB) and a body (4 KiB)
  int workers = 8;
  int nice = 10;  // 0-19; raising a thread's nice value needs no privilege
};

// Sets the calling thread's nice value (Linux: per thread). False when the kernel refused.
bool set_thread_nice(int nice);
// What each of the view's threads does first: names itself `name` (at most 15 characters, as
// /proc/PID/task/TID/comm and `top -H` show it, so its CPU time can be told from the loop's),
// leaves any scheduling policy it inherited (SCHED_FIFO / RR from a raised creator, SCHED_BATCH,
// SCHED_IDLE) for SCHED_OTHER, and sets `nice`: the view's threads run below every loop thread of
// the run, never at a real-time priority. False when the kernel refused a step (the rest is done),
// after one spdlog warning naming the thread and each refused step with its errno.
bool enter_view_thread(const char* name, int nice);

class RequestGate {
 public:
  // Starts the epoll thread and the workers. Throws std::runtime_error when epoll cannot start.
  RequestGate(GateOptions options, std::function<void(int fd)> serve);
  ~RequestGate();  // stop()
  RequestGate(const RequestGate&) = delete;
  RequestGate& operator=(const RequestGate&) = delete;

  // Takes ownership of `fd` (a connected socket).
  void admit(int fd);
  // Closes every waiting and queued connection, lets running `serve` calls return, joins.
  void stop();
  nlohmann::json counters() const;

 private:
  enum class Peek { kIncomplete, kComplete, kClosed, kTooLarge };
  struct Peeked {
    Peek state = Peek::kIncomplete;
    std::size_t bytes = 0;  // request bytes in the socket
  };
  Peeked peek(int fd) const;
  void poll_loop();
  void on_readable(int fd);
  // @pre mutex_ held. Displaces waiting connections until a new one from `address` fits; those
  // found complete (or closed) meanwhile leave the table into `found`, to be finished unlocked.
  void make_room(std::uint32_t address, std::vector<std::pair<int, Peek>>& found);
  // A connection out of the table with its request `state`: served, refused or closed.
  void finish(int fd, Peek state);
  void expire(std::chrono::steady_clock::time_point now);
  void forget(int fd);  // @pre mutex_ held: leaves the table and epoll, not closed
  void enqueue(int fd);
  void worker_loop();

  GateOptions options_;
  std::function<void(int)> serve_;
  int epoll_ = -1;
  mutable std::mutex mutex_;
  std::condition_variable queued_cv_;
  Admission waiting_;  // connections whose request is not complete yet
  std::deque<int> queue_;
  bool stopping_ = false;
  std::thread poller_;
  std::vector<std::thread> workers_;
  std::uint64_t admitted_ = 0, served_ = 0, timed_out_ = 0, evicted_ = 0, too_large_ = 0,
                closed_early_ = 0, queue_full_ = 0;
};

}  // namespace rths::view
