#pragma once
// Admission: which waiting connection the view's front door (RequestGate) lets go when a new one
// arrives and there is no room. Pure bookkeeping: no sockets, no clock; the gate tells it what
// arrived, what bytes it has seen and when, and acts on the answer.
//
// State: the connections whose request is not complete yet, in arrival order, each with its
// peer's IPv4 address, its arrival, the request bytes seen so far and when that count last grew
// (its arrival while it has sent nothing).
// Rule, for a new connection from address A (displaced_by):
//   - room: fewer than max_waiting wait, and fewer than max_per_address of them are from A:
//     nothing is displaced. max_per_address < max_waiting keeps slots free for other addresses,
//     so one host, however fast it connects, only ever displaces its own connections;
//   - else the candidates are A's own connections when A is at its limit, else every waiting one;
//     of them, the one idle longest: any that has sent nothing before any that has (a browser
//     sends its request within a round trip of connecting; a connection that has sent part of
//     one is more likely a slow client than a hog), then the longest since its byte count last
//     grew (its arrival when it has sent nothing).
// The new connection is never the one displaced: it is not in the table when the choice is made,
// and once added it is the newest, so it goes last among those that sent nothing. What the table
// knows of bytes can lag behind the socket: the gate checks the chosen one's socket and, when its
// count grew (saw_bytes returns true), asks again (RequestGate::make_room).
// Thread safety: none; the gate holds its mutex around every call.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <list>
#include <optional>
#include <unordered_map>
#include <vector>

namespace rths::view {

struct AdmissionLimits {
  std::size_t max_waiting = 64;      // connections whose request is not complete yet (>= 1)
  std::size_t max_per_address = 56;  // of them from one peer address (1 to max_waiting)
};

class Admission {
 public:
  using Clock = std::chrono::steady_clock;

  explicit Admission(AdmissionLimits limits);

  // The connection a new one from `address` must displace before it is added; nothing when there
  // is room.
  std::optional<int> displaced_by(std::uint32_t address) const;
  // @pre `fd` is not waiting.
  void add(int fd, std::uint32_t address, Clock::time_point now);
  // `bytes`: how many request bytes the socket holds now. True when that is more than the table
  // knew (the connection was active at `now`); false when unchanged or `fd` is not waiting.
  bool saw_bytes(int fd, std::size_t bytes, Clock::time_point now);
  // False when `fd` was not waiting.
  bool remove(int fd);
  // Removes and returns those that arrived at or before `cutoff`, oldest first.
  std::vector<int> take_arrived_by(Clock::time_point cutoff);
  bool contains(int fd) const { return at_.count(fd) > 0; }
  std::size_t size() const { return waiting_.size(); }
  std::size_t from(std::uint32_t address) const;
  std::vector<int> fds() const;  // oldest first

 private:
  struct Waiting {
    int fd;
    std::uint32_t address;
    Clock::time_point arrived, active;  // active: when `bytes` last grew (arrived while 0)
    std::size_t bytes;
  };
  // Whether `a` has been idle longer than `b` by the rule above.
  static bool idler(const Waiting& a, const Waiting& b);

  AdmissionLimits limits_;
  std::list<Waiting> waiting_;  // arrival order
  std::unordered_map<int, std::list<Waiting>::iterator> at_;
};

}  // namespace rths::view
