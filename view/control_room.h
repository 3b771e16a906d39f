#pragma once
// The control room of a distributed test (issue 66): who may press what on the view, and the
// presses on their way from the view's threads to the loop.
//
// Roles, each with its own token (make_token: 128 random bits, made per run):
//   director   HOLD every lab or any one, STOP the test
//   operator   of one lab: HOLD that lab's actuators (the lab's nodes that drive actuators); never
//              STOP, never another lab, never release: nothing releases a HOLD (a node's HOLD
//              freezes it for the rest of the run); the held run waits for the director's STOP
//   viewer     sees, as everyone who reaches the view does; every press is refused
// Inputs: the labs (site name -> the ids of its nodes that drive actuators, in the sites
// config's order), a Crew of tokens, and presses: a token, an action ("stop" or "hold") and, for
// a HOLD, a lab ("" = every lab).
// Outputs: per press a Press (who, what, allowed or why refused, the nodes to HOLD, whether to
// STOP, CLOCK_REALTIME ns). A token of no role is refused and queues nothing (the server counts
// it); every press of a known role, allowed or refused, queues for the loop, which polls
// pending() once per step (one relaxed atomic load) and take()s them only when it is set: each
// becomes a record event; an allowed HOLD is sent to its nodes at once and holds the run (the
// loop integrates no further step: it cannot integrate past a held actuator) until an allowed
// STOP ends it (HOLD, then STOP).
// Thread safety: press(), pending(), take() from any thread; Crew is a value.

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rths::view {

// 32 hex digits (128 bits) from the kernel's random source (getrandom). Throws
// std::runtime_error when it has none.
std::string make_token();

struct Role {
  enum class Kind { kDirector, kOperator, kViewer };
  Kind kind = Kind::kViewer;
  std::string lab;           // an operator's lab
  std::string name() const;  // "the director", "the operator of lab_b", "a viewer"
};

// The run's tokens, one per role (each at least 16 characters).
struct Crew {
  std::string director, viewer;
  std::map<std::string, std::string> operators;  // lab -> its operator's token
  // Fresh tokens for the director, a viewer and each lab's operator.
  static Crew make(const std::vector<std::string>& labs);
  // The role whose token `token` is (compared in constant time), none for any other.
  std::optional<Role> identify(const std::string& token) const;
  // {"director": T, "viewer": T, "operators": {"lab": T}}: how a launcher hands the crew to the
  // coordinator (its environment, never a command line).
  nlohmann::json to_json() const;
  // Throws std::invalid_argument naming the field missing or a token under 16 characters.
  static Crew from_json(const nlohmann::json& j);
};

struct Press {
  std::string who;   // Role::name()
  std::string what;  // "STOP", "HOLD of lab_b", "HOLD of every lab"
  bool allowed = false;
  std::string why;              // refused: why
  std::vector<int> hold_nodes;  // an allowed HOLD: the nodes to HOLD
  bool stop = false;            // an allowed STOP
  std::int64_t realtime_ns = 0;
  // The newest step the view had seen when it was pressed (-1: none): the loop's step then was
  // at least this, so the steps from it to the one that applied the press bound the delay.
  std::int64_t seen_step = -1;
  std::string text() const;  // the record event's words
};

class ControlDesk {
 public:
  // `labs`: site name -> its nodes that drive actuators. Throws std::invalid_argument when the
  // crew has an operator of a lab not in `labs`.
  ControlDesk(Crew crew, std::map<std::string, std::vector<int>> labs);

  // Judges one press. No role (unknown token): nullopt, nothing queued. An unknown action or lab
  // is refused, naming it.
  std::optional<Press> press(const std::string& token, const std::string& action,
                             const std::string& lab, std::int64_t seen_step = -1);
  bool pending() const { return pending_.load(std::memory_order_relaxed); }
  std::vector<Press> take();  // the queued presses, oldest first
  const std::map<std::string, std::vector<int>>& labs() const { return labs_; }
  const Crew& crew() const { return crew_; }

 private:
  Press judge(const Role& role, const std::string& action, const std::string& lab) const;
  Crew crew_;
  std::map<std::string, std::vector<int>> labs_;
  std::mutex mutex_;
  std::vector<Press> queued_;
  std::atomic<bool> pending_{false};
};

}  // namespace rths::view
