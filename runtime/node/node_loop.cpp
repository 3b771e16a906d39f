#include "runtime/node/node_loop.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "runtime/node/hold_cause.h"
#include "runtime/node/lag.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "runtime/rt/clock.h"
#include "runtime/rt/fifo.h"
#include "runtime/rt/pacing.h"
#include "transport/dds_endpoint.h"

namespace rths::runtime {
namespace {

using transport::realtime_ns;

std::int64_t seconds_to_ns(double s) { return static_cast<std::int64_t>(s * 1e9); }

// A message waiting for its lag to pass: inbound (receive lag, then the service) or outbound
// (send lag, then the wire).
struct Delayed {
  std::int64_t release_ns;
  transport::Message message;
  double injected;  // s, receive lag drawn for it
};

// What the assignment sets: timers and the lag injectors of the node's link.
struct Assigned {
  std::int64_t heartbeat_ns = seconds_to_ns(0.05), orphan_ns = seconds_to_ns(5.0);
  std::int64_t watchdog_ns = 0;  // real-time actuator emulators only; 0 = off
  std::unique_ptr<LagInjector> receive_lag, send_lag;
};

// The loop of one node process around its service (the contract is in node_loop.h).
//   set-up     the constructor: nothing assigned, announcing.
//   each pass  keep_time (announce, heartbeat, watchdog, orphan) -> write what is due ->
//              apply what is due -> wait for a message or the next thing due, and take it.
//   teardown   the destructor: the servo thread is stopped and joined, then the inline handler
//              removed (waiting out a running call), before any state it touches goes.
// `state` guards the service and the timers against the inline handler, the servo thread and the
// answer thread; the loop holds it except while it waits (node_loop.h, Threads).
class NodeLoop {
 public:
  NodeLoop(transport::Endpoint& endpoint, NodeService& service, const NodeLoopOptions& options)
      : endpoint_(endpoint), service_(service), options_(options), lock_(state_) {}
  ~NodeLoop();

  // The exit code when the node must leave now (never assigned, orphaned), else nullopt.
  // Loop thread, lock held. Real time: no allocation unless it announces, holds or leaves; may
  // release the lock for kWatchdogGrace before the watchdog judges.
  std::optional<int> keep_time();
  // Loop thread, lock held: sends the replies whose send lag has passed.
  void write_due();
  // The exit code once a STOP was applied, else nullopt. Loop thread, lock held; a lagged
  // message's replies are queued (allocates), an unlagged one's sent from the service's buffer.
  std::optional<int> apply_due();
  // Loop thread: releases the lock while it waits for a message or the next thing due.
  void wait_and_take();

 private:
  // A message off the transport: stamps what the watchdogs watch, then waits its receive lag.
  // Loop thread, lock held; queues the message (allocates).
  void take(transport::Message message);
  // Loop thread, lock held: the service handles one released message.
  void apply(Delayed item);
  // Loop thread, lock held, once per run (set-up: allocates, starts threads).
  void on_assigned();
  // Loop thread, lock held; releases it for kWatchdogGrace when the watchdog is due.
  bool commands_stopped(std::int64_t now);
  // Set-up; the servo thread's pass takes the lock once a period and allocates nothing.
  void start_servo(double period, const WaitPolicy& policy);
  // Set-up; the answer thread waits unlocked and forwards under the lock, allocating nothing
  // once warm (NodeService::take_answers).
  void start_answers();
  // Stopped: an asynchronous node comes to rest on its answer thread (a controller holds until
  // its rig says held); the loop waits for it, lock released, and sends its final heartbeat.
  // Loop thread; teardown only, so it may sleep.
  void wait_for_rest();
  // Receive thread, takes the lock: a COMMAND with no lag injected, handled and answered there
  // (no allocation once warm). False: not handled (the loop takes it).
  bool handle_inline(const transport::Message& m);

  transport::Endpoint& endpoint_;
  NodeService& service_;
  const NodeLoopOptions options_;
  std::mutex state_;
  std::unique_lock<std::mutex> lock_;
  std::deque<Delayed> inbound_, outbound_;
  Assigned assigned_;
  const std::int64_t started_ = realtime_ns();
  std::int64_t next_announce_ = 0, next_heartbeat_ = 0;
  std::int64_t last_from_coordinator_ = started_, last_command_ns_ = 0;
  std::atomic<bool> stop_servo_{false};
  std::thread servo_, answers_;
  std::optional<runtime::FifoThreads> fifo_;  // realtime_priority: the node's threads raised
  // The service's replies straight onto the wire (built once: no allocation per command).
  const NodeService::Send send_ = [this](const transport::Message& m) { endpoint_.send(m); };
};

NodeLoop::~NodeLoop() {
  stop_servo_ = true;
  for (std::thread* t : {&servo_, &answers_}) {
    if (!t->joinable()) continue;
    if (lock_.owns_lock()) lock_.unlock();
    t->join();
  }
  if (lock_.owns_lock()) lock_.unlock();
  endpoint_.set_inline_handler(nullptr);
}

// Commands without injected lag are handled on the transport's receive thread (no thread switch
// per step).
bool NodeLoop::handle_inline(const transport::Message& m) {
  if (m.kind != COMMAND) return false;
  std::lock_guard guard(state_);
  if (m.run_id == service_.run_id()) last_from_coordinator_ = last_command_ns_ = m.received_ns;
  service_.set_injected_lag(0.0);
  service_.handle(m, send_);
  return true;
}

// The servo loop of a streaming node (real time, servo faster than the integrator): its own
// thread, paced on CLOCK_MONOTONIC with the deployment's wait policy, one servo_tick() per
// period under `state_`.
void NodeLoop::start_servo(double period, const WaitPolicy& policy) {
  servo_ = std::thread([this, period, policy] {
    MonotonicClock clock;
    Pacer pacer(clock, period, policy);
    pacer.start();
    for (std::int64_t k = 1; !stop_servo_; ++k) {
      const PaceResult pace = pacer.wait(k);
      std::lock_guard guard(state_);
      if (auto feedback = service_.servo_tick(pace.overrun)) endpoint_.send(*feedback);
    }
  });
}

// The answers of an asynchronous node: its own thread waits on the node's source (no lock),
// then takes what came under `state_` and sends it at once. It wakes at least every
// kAnswerPoll, which paces the node's own checks (a controller's lost frames, its HOLD frames).
constexpr std::int64_t kAnswerPoll = 500000;  // ns

void NodeLoop::start_answers() {
  answers_ = std::thread([this] {
    while (!stop_servo_) {
      service_.await_answers(monotonic_ns() + kAnswerPoll);
      std::lock_guard guard(state_);
      service_.take_answers(send_);
    }
  });
}

void NodeLoop::wait_for_rest() {
  // The node's own hold time bounds its rest; this only keeps a faulty node from hanging here.
  constexpr std::int64_t kRestLimit = 70'000'000'000;  // ns
  const std::int64_t until = realtime_ns() + kRestLimit;
  while (!service_.at_rest() && realtime_ns() < until) {
    lock_.unlock();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    lock_.lock();
  }
  if (auto final = service_.final_heartbeat_due()) endpoint_.send(*final);
}

void NodeLoop::take(transport::Message message) {
  // Never back in time: a message that queued while the node set itself up (its part built on
  // the Assign, after which the orphan clock restarts) arrived before that restart.
  if (service_.assigned() && message.run_id == service_.run_id()) {
    last_from_coordinator_ = std::max(last_from_coordinator_, message.received_ns);
    if (message.kind == COMMAND) last_command_ns_ = std::max(last_command_ns_, message.received_ns);
  }
  if (!assigned_.receive_lag) {
    inbound_.push_back({message.received_ns, std::move(message), 0.0});
    return;
  }
  const auto release = assigned_.receive_lag->schedule(
      message.received_ns, message.kind == COMMAND ? message.step : std::int64_t{-1});
  if (!release) return;  // lost
  inbound_.push_back({*release, std::move(message), assigned_.receive_lag->last_delay()});
}

// Whether no command has arrived for the watchdog's time. A node that was itself descheduled
// wakes with commands waiting on its receive thread: it lets that thread deliver them (a grace
// of kWatchdogGrace, lock released) and takes what is queued before it judges the coordinator
// silent, so its own stall is not read as the coordinator's. A true silence holds at most the
// grace later.
bool NodeLoop::commands_stopped(std::int64_t now) {
  const std::int64_t watchdog = assigned_.watchdog_ns;
  if (watchdog <= 0 || last_command_ns_ <= 0 || service_.held() ||
      now - last_command_ns_ <= watchdog)
    return false;
  lock_.unlock();
  std::this_thread::sleep_for(kWatchdogGrace);
  lock_.lock();
  while (auto queued = endpoint_.receive(std::chrono::nanoseconds(0))) take(std::move(*queued));
  return !service_.held() && realtime_ns() - last_command_ns_ > watchdog;
}

std::optional<int> NodeLoop::keep_time() {
  const std::int64_t now = realtime_ns();
  if (!service_.assigned()) {
    if (now >= next_announce_) {
      endpoint_.send(service_.announce());
      next_announce_ = now + seconds_to_ns(options_.announce_period);
    }
    if (now - started_ <= seconds_to_ns(options_.assign_timeout)) return std::nullopt;
    spdlog::error("{}: no coordinator assigned this node within {} s", service_.label(),
                  options_.assign_timeout);
    return 1;
  }
  if (now >= next_heartbeat_) {
    endpoint_.send(service_.heartbeat());
    next_heartbeat_ = now + assigned_.heartbeat_ns;
  }
  if (commands_stopped(now)) {
    const double silent_ms = static_cast<double>(realtime_ns() - last_command_ns_) * 1e-6;
    if (auto hold = service_.hold_on_own(
            std::string(kCommandWatchdogCause) + std::to_string(silent_ms) + " ms (limit " +
            std::to_string(static_cast<double>(assigned_.watchdog_ns) * 1e-6) + " ms)"))
      endpoint_.send(*hold);
  }
  if (now - last_from_coordinator_ <= assigned_.orphan_ns) return std::nullopt;
  spdlog::error("{}: coordinator silent for {:.3f} s; holding and leaving", service_.label(),
                static_cast<double>(now - last_from_coordinator_) * 1e-9);
  if (auto hold = service_.hold_on_own("coordinator silent")) endpoint_.send(*hold);
  service_.settle_hold();
  if (service_.asynchronous()) wait_for_rest();
  return 1;
}

void NodeLoop::write_due() {
  const std::int64_t now = realtime_ns();
  while (!outbound_.empty() && outbound_.front().release_ns <= now) {
    endpoint_.send(outbound_.front().message);
    outbound_.pop_front();
  }
}

// The service handles the message; its replies leave now, or after the send lag.
void NodeLoop::apply(Delayed item) {
  if (!assigned_.send_lag) {
    service_.set_injected_lag(item.injected);
    service_.handle(item.message, send_);
    return;
  }
  const auto release = assigned_.send_lag->schedule(
      realtime_ns(), item.message.kind == COMMAND ? item.message.step : std::int64_t{-1});
  service_.set_injected_lag(item.injected + assigned_.send_lag->last_delay());
  auto replies = service_.handle(item.message);
  if (!release) return;  // the replies are lost on the way out
  for (auto& r : replies) outbound_.push_back({*release, std::move(r), 0.0});
}

// Set-up of the run the node was just assigned: timers, the link's lag injectors, the command
// watchdog, the servo thread, and the inline fast path when no lag is injected.
void NodeLoop::on_assigned() {
  const Assign& a = service_.assignment();
  assigned_.heartbeat_ns = seconds_to_ns(a.heartbeat_period() > 0 ? a.heartbeat_period() : 0.05);
  assigned_.orphan_ns = seconds_to_ns(a.orphan_timeout() > 0 ? a.orphan_timeout() : 5.0);
  if (LagInjector in(a.node().receive_lag()); in.active())
    assigned_.receive_lag = std::make_unique<LagInjector>(a.node().receive_lag(), a.dt());
  if (LagInjector out(a.node().send_lag()); out.active())
    assigned_.send_lag = std::make_unique<LagInjector>(a.node().send_lag(), a.dt());
  last_from_coordinator_ = realtime_ns();
  const config::Deployment& deployment = a.study().deployment();
  if (drives_actuators(a.node().kind()) && deployment.clock() == config::Deployment::REAL_TIME)
    assigned_.watchdog_ns = seconds_to_ns(command_watchdog_periods(deployment, a.dt()) * a.dt());
  spdlog::info("{}: assigned to run {}", service_.label(), service_.run_id());
  // Before the servo and answer threads start, which inherit the loop's policy.
  if (const int priority = realtime_priority(deployment); priority > 0)
    spdlog::info("{}: {}", service_.label(),
                 fifo_.emplace(priority, "loop", transport::dds_receive_thread_names()).summary());
  if (service_.streaming()) {
    const double period = service_.streaming_period();
    spdlog::info("{}: servo loop at {:.0f} Hz ({} policy)", service_.label(), 1.0 / period,
                 to_string(wait_policy(deployment).kind));
    start_servo(period, wait_policy(deployment));
  }
  if (service_.asynchronous()) start_answers();
  if (!assigned_.receive_lag && !assigned_.send_lag)
    endpoint_.set_inline_handler([this](const transport::Message& m) { return handle_inline(m); });
}

std::optional<int> NodeLoop::apply_due() {
  const std::int64_t now = realtime_ns();
  while (!inbound_.empty() && inbound_.front().release_ns <= now) {
    Delayed item = std::move(inbound_.front());
    inbound_.pop_front();
    const bool was_assigned = service_.assigned();
    apply(std::move(item));
    if (!was_assigned && service_.assigned()) on_assigned();
    if (service_.stopped()) {
      for (auto& d : outbound_) endpoint_.send(d.message);
      service_.settle_hold();
      if (service_.asynchronous()) wait_for_rest();
      spdlog::info("{}: stopped after step {} ({} messages rejected)", service_.label(),
                   service_.last_step(), service_.rejected().total());
      return 0;
    }
  }
  service_.settle_hold();  // after a hold was reported (no-op otherwise, and after the first)
  return std::nullopt;
}

// Sleeps until the next thing due, or a message, which it takes.
void NodeLoop::wait_and_take() {
  std::int64_t wake = service_.assigned() ? next_heartbeat_ : next_announce_;
  if (assigned_.watchdog_ns > 0 && last_command_ns_ > 0 && !service_.held())
    wake = std::min(wake, last_command_ns_ + assigned_.watchdog_ns + 1);
  if (!inbound_.empty()) wake = std::min(wake, inbound_.front().release_ns);
  if (!outbound_.empty()) wake = std::min(wake, outbound_.front().release_ns);
  const auto timeout = std::chrono::nanoseconds(std::max<std::int64_t>(0, wake - realtime_ns()));
  lock_.unlock();
  auto message = endpoint_.receive(timeout);
  lock_.lock();
  if (message) take(std::move(*message));
}

}  // namespace

int run_node(transport::Endpoint& endpoint, NodeService& service, const NodeLoopOptions& options) {
  NodeLoop loop(endpoint, service, options);
  for (;;) {
    if (const auto code = loop.keep_time()) return *code;
    loop.write_due();
    if (const auto code = loop.apply_due()) return *code;
    loop.wait_and_take();
  }
}

}  // namespace rths::runtime
