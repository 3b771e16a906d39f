#include "runtime/node_loop.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include "runtime/pacing.h"

#include "runtime/lag.h"
#include "runtime/plan.h"
#include "runtime/schema.h"

namespace rths::runtime {
namespace {

struct Delayed {
  std::int64_t release_ns;
  transport::Message message;
  double injected;  // s, receive lag drawn for it
};

std::int64_t seconds_to_ns(double s) { return static_cast<std::int64_t>(s * 1e9); }

}  // namespace



int run_node(transport::Endpoint& endpoint, NodeService& service, const NodeLoopOptions& options) {
  using transport::realtime_ns;
  std::deque<Delayed> inbound, outbound;
  std::unique_ptr<LagInjector> receive_lag, send_lag;
  std::int64_t next_announce = 0, next_heartbeat = 0;
  const std::int64_t started = realtime_ns();
  std::int64_t last_from_coordinator = started;
  std::int64_t heartbeat_ns = seconds_to_ns(0.05), orphan_ns = seconds_to_ns(5.0);
  // Command watchdog (real-time actuator emulators only; 0 = off): armed by the first command.
  std::int64_t watchdog_ns = 0, last_command_ns = 0;

  // Commands without injected lag are handled inline, on the transport's receive thread (no
  // thread switch per step); `state` guards the service and last_from_coordinator against this
  // loop. Declaration order matters: the lock is released before the handler is removed, and the
  // handler is removed (waiting for a running invocation) before anything it touches goes.
  std::mutex state;
  struct RemoveHandler {
    transport::Endpoint& endpoint;
    ~RemoveHandler() { endpoint.set_inline_handler(nullptr); }
  } remove_handler{endpoint};
  const auto handle_inline = [&](const transport::Message& m) {
    if (m.kind != COMMAND) return false;
    std::lock_guard guard(state);
    if (m.run_id == service.run_id()) last_from_coordinator = last_command_ns = m.received_ns;
    service.set_injected_lag(0.0);
    for (auto& r : service.handle(m)) endpoint.send(r);
    return true;
  };
  std::unique_lock lock(state);

  // The servo loop of a streaming node (real time, servo faster than the integrator): its own
  // thread, paced on CLOCK_MONOTONIC with the deployment's wait policy, one servo_tick() per
  // period under `state`. Stopped and joined (with `state` released) whenever run_node returns.
  struct ServoThread {
    std::unique_lock<std::mutex>& lock;
    std::atomic<bool> stop{false};
    std::thread thread;
    ~ServoThread() {
      stop = true;
      if (!thread.joinable()) return;
      if (lock.owns_lock()) lock.unlock();
      thread.join();
    }
  } servo{lock, {false}, {}};
  const auto start_servo = [&](double period, const WaitPolicy& policy) {
    servo.thread = std::thread([&, period, policy] {
      MonotonicClock clock;
      Pacer pacer(clock, period, policy);
      pacer.start();
      for (std::int64_t k = 1; !servo.stop; ++k) {
        const PaceResult pace = pacer.wait(k);
        std::lock_guard guard(state);
        if (auto feedback = service.servo_tick(pace.overrun)) endpoint.send(*feedback);
      }
    });
  };

  // A message off the transport: stamps what the watchdogs watch, then waits its receive lag.
  const auto take = [&](transport::Message message) {
    if (service.assigned() && message.run_id == service.run_id()) {
      last_from_coordinator = message.received_ns;
      if (message.kind == COMMAND) last_command_ns = message.received_ns;
    }
    if (receive_lag) {
      const auto release = receive_lag->schedule(message.received_ns);
      if (!release) return;  // lost
      inbound.push_back({*release, std::move(message), receive_lag->last_delay()});
    } else {
      inbound.push_back({message.received_ns, std::move(message), 0.0});
    }
  };
  // Whether no command has arrived for the watchdog's time. A node that was itself descheduled
  // wakes with commands waiting on its receive thread: it lets that thread deliver them (a grace
  // of kWatchdogGrace, lock released) and takes what is queued before it judges the coordinator
  // silent, so its own stall is not read as the coordinator's. A true silence holds at most the
  // grace later.
  const auto commands_stopped = [&](std::int64_t now) {
    if (watchdog_ns <= 0 || last_command_ns <= 0 || service.held() || now - last_command_ns <= watchdog_ns)
      return false;
    lock.unlock();
    std::this_thread::sleep_for(kWatchdogGrace);
    lock.lock();
    while (auto queued = endpoint.receive(std::chrono::nanoseconds(0))) take(std::move(*queued));
    return !service.held() && realtime_ns() - last_command_ns > watchdog_ns;
  };

  for (;;) {
    const std::int64_t now = realtime_ns();
    if (!service.assigned()) {
      if (now >= next_announce) {
        endpoint.send(service.announce());
        next_announce = now + seconds_to_ns(options.announce_period);
      }
      if (now - started > seconds_to_ns(options.assign_timeout)) {
        spdlog::error("{}: no coordinator assigned this node within {} s", service.label(),
                      options.assign_timeout);
        return 1;
      }
    } else {
      if (now >= next_heartbeat) {
        endpoint.send(service.heartbeat());
        next_heartbeat = now + heartbeat_ns;
      }
      if (commands_stopped(now)) {
        const double silent_ms = static_cast<double>(realtime_ns() - last_command_ns) * 1e-6;
        if (auto hold = service.hold_on_own(
                "command watchdog: no fresh command for " + std::to_string(silent_ms) +
                " ms (limit " + std::to_string(static_cast<double>(watchdog_ns) * 1e-6) + " ms)"))
          endpoint.send(*hold);
      }
      if (now - last_from_coordinator > orphan_ns) {
        spdlog::error("{}: coordinator silent for {:.3f} s; holding and leaving", service.label(),
                      static_cast<double>(now - last_from_coordinator) * 1e-9);
        if (auto hold = service.hold_on_own("coordinator silent")) endpoint.send(*hold);
        service.settle_hold();
        return 1;
      }
    }
    // Send what is due, then apply what has arrived and is due.
    while (!outbound.empty() && outbound.front().release_ns <= now) {
      endpoint.send(outbound.front().message);
      outbound.pop_front();
    }
    while (!inbound.empty() && inbound.front().release_ns <= now) {
      Delayed item = std::move(inbound.front());
      inbound.pop_front();
      const bool was_assigned = service.assigned();
      std::int64_t send_at = realtime_ns();
      double injected = item.injected;
      if (send_lag) {
        const auto release = send_lag->schedule(send_at);
        injected += send_lag->last_delay();
        service.set_injected_lag(injected);
        auto replies = service.handle(item.message);
        if (!release) continue;  // the replies are lost on the way out
        for (auto& r : replies) outbound.push_back({*release, std::move(r), 0.0});
      } else {
        service.set_injected_lag(injected);
        for (auto& r : service.handle(item.message)) endpoint.send(r);
      }
      if (!was_assigned && service.assigned()) {
        const Assign& a = service.assignment();
        heartbeat_ns = seconds_to_ns(a.heartbeat_period() > 0 ? a.heartbeat_period() : 0.05);
        orphan_ns = seconds_to_ns(a.orphan_timeout() > 0 ? a.orphan_timeout() : 5.0);
        if (LagInjector in(a.node().receive_lag()); in.active())
          receive_lag = std::make_unique<LagInjector>(a.node().receive_lag());
        if (LagInjector out(a.node().send_lag()); out.active())
          send_lag = std::make_unique<LagInjector>(a.node().send_lag());
        last_from_coordinator = realtime_ns();
        const config::Deployment& deployment = a.study().deployment();
        if (a.node().kind() == config::NodeSpec::ACTUATOR_EMULATOR &&
            deployment.clock() == config::Deployment::REAL_TIME)
          watchdog_ns = seconds_to_ns(command_watchdog_periods(deployment) * a.dt());
        spdlog::info("{}: assigned to run {}", service.label(), service.run_id());
        if (service.streaming()) {
          const double period = service.streaming_period();
          spdlog::info("{}: servo loop at {:.0f} Hz ({} policy)", service.label(), 1.0 / period,
                       to_string(wait_policy(deployment).kind));
          start_servo(period, wait_policy(deployment));
        }
        if (!receive_lag && !send_lag) endpoint.set_inline_handler(handle_inline);
      }
      if (service.stopped()) {
        for (auto& d : outbound) endpoint.send(d.message);
        service.settle_hold();
        spdlog::info("{}: stopped after step {} ({} messages rejected)", service.label(),
                     service.last_step(), service.rejected().total());
        return 0;
      }
    }
    service.settle_hold();  // after a hold was reported (no-op otherwise, and after the first)
    // Sleep until the next thing due, or a message.
    std::int64_t wake = service.assigned() ? next_heartbeat : next_announce;
    if (watchdog_ns > 0 && last_command_ns > 0 && !service.held())
      wake = std::min(wake, last_command_ns + watchdog_ns + 1);
    if (!inbound.empty()) wake = std::min(wake, inbound.front().release_ns);
    if (!outbound.empty()) wake = std::min(wake, outbound.front().release_ns);
    const auto timeout = std::chrono::nanoseconds(std::max<std::int64_t>(0, wake - realtime_ns()));
    lock.unlock();
    auto message = endpoint.receive(timeout);
    lock.lock();
    if (message) take(std::move(*message));
  }
}

}  // namespace rths::runtime
