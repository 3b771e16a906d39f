#include "controller_emulator/controller_emulator.h"

#include <spdlog/spdlog.h>
#include <sys/prctl.h>

#include <atomic>
#include <cmath>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "controller_node/controller_exchange.h"
#include "controller_node/frame.h"
#include "controller_node/udp_link.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "runtime/rt/clock.h"
#include "runtime/rt/pacing.h"

namespace rths::controller_emulator {
namespace {

using controller_node::Direction;
using controller_node::FrameValues;
using controller_node::FrameVerdict;

const char* const kRunId = "controller-emulator";

// The Assign the coordinator would send the node, as an actuator emulator's: the node's own
// delay stages and link lags left out (the controller node applies those itself). The clock is
// lockstep, so the actuators answer each command once (their servo periods in simulated time),
// unless the deployment is real time with a servo faster than the integrator: then real time,
// so that the actuators stream (load on a command, one servo period per tick) and are paced.
runtime::Assign assignment(const config::Study& study, const std::filesystem::path& base_dir,
                           const std::string& case_name, int node_id) {
  const study::PreparedStudy prepared = study::prepare_study(study, base_dir);
  const config::Case& study_case = study::find_case(study, case_name);
  const core::HybridSetup setup = study::setup_for_case(prepared, study_case);
  const config::Deployment deployment = runtime::with_default_nodes(study.deployment(), setup);
  const runtime::DeploymentPlan plan = runtime::make_plan(setup, deployment);
  const runtime::NodePlan* node = plan.find(node_id);
  if (!node || node->spec.kind() != config::NodeSpec::CONTROLLER)
    throw std::invalid_argument("node " + std::to_string(node_id) +
                                " is not a CONTROLLER of the study's deployment");
  runtime::Assign assign;
  assign.set_schema_version(runtime::kSchemaVersion);
  *assign.mutable_study() = study;
  const bool paced =
      study.deployment().clock() == config::Deployment::REAL_TIME && setup.servo_substeps > 1;
  assign.mutable_study()->mutable_deployment()->set_clock(paced ? config::Deployment::REAL_TIME
                                                                : config::Deployment::LOCKSTEP);
  assign.set_base_dir(base_dir.string());
  assign.set_case_name(study_case.name());
  config::NodeSpec& spec = *assign.mutable_node();
  spec.set_id(node_id);
  spec.set_kind(config::NodeSpec::ACTUATOR_EMULATOR);
  assign.set_dt(setup.dt);
  for (int s : node->storeys) assign.add_storeys(s);
  for (int a : node->actuators) assign.add_actuators(a);
  return assign;
}

}  // namespace

ControllerEmulator::ControllerEmulator(const config::Study& study,
                                       const std::filesystem::path& base_dir,
                                       const std::string& case_name, int node_id,
                                       std::int64_t answer_frames)
    : answer_frames_(answer_frames) {
  for (const config::NodeSpec& spec : study.deployment().nodes())
    if (spec.id() == node_id) link_ = spec.controller();
  const runtime::Assign assign = assignment(study, base_dir, case_name, node_id);
  actuators_ = assign.actuators_size();
  runtime::check_frame_layout(link_.command(), actuators_, Direction::kCommand,
                              "controller.command");
  runtime::check_frame_layout(link_.feedback(), actuators_, Direction::kFeedback,
                              "controller.feedback");
  for (const auto* layout : {&link_.command(), &link_.feedback()})
    if (controller_node::frame_size(*layout) > controller_node::kMaxDatagram)
      throw std::invalid_argument("controller: a frame longer than a datagram is read");
  wait_policy_ = runtime::wait_policy(study.deployment());
  plant_realised_.assign(static_cast<std::size_t>(actuators_), 0.0);
  plant_force_ = plant_realised_;
  service_ = std::make_unique<actuator_emulator::ActuatorService>(node_id, kRunId);
  const auto ready = service_->handle(runtime::pack(kRunId, node_id, runtime::ASSIGN, 0, assign));
  runtime::Ready r;
  if (ready.empty() || !runtime::unpack(ready.front(), r) || !r.error().empty())
    throw std::invalid_argument("the actuators refused their part: " + r.error());
}

ControllerEmulator::~ControllerEmulator() = default;

std::optional<std::vector<std::uint8_t>> ControllerEmulator::step(const std::uint8_t* data,
                                                                  std::size_t size) {
  FrameValues in;
  const FrameVerdict verdict = controller_node::decode(link_.command(), data, size, actuators_, in);
  if (verdict != FrameVerdict::kOk) {
    ++counts_.rejected;
    spdlog::warn("controller emulator: command frame rejected: {} ({} bytes)",
                 controller_node::to_string(verdict), size);
    return std::nullopt;
  }
  const int id = service_->node_id();
  if (in.status == controller_node::kStatusStop) {
    ++counts_.stops;
    spdlog::info("controller emulator: status STOP received (frame {})", in.counter);
    return std::nullopt;
  }
  if (in.status == controller_node::kStatusHold) {
    ++counts_.holds;
    if (!holding_ || counts_.holds == 1)
      spdlog::warn("controller emulator: status HOLD received (frame {}); actuators hold",
                   in.counter);
    service_->handle(runtime::pack(kRunId, id, runtime::HOLD, step_, runtime::Hold{}));
    service_->settle_hold();
    holding_ = true;
    return held_answer(in);
  }
  ++counts_.commands;
  if (answer_frames_ >= 0 && static_cast<std::int64_t>(counts_.answered) >= answer_frames_)
    return std::nullopt;  // gone silent
  FrameValues out = in;
  out.status = controller_node::kStatusRun;
  runtime::Feedback feedback;
  if (!holding_ && !command_actuators(in, feedback))
    holding_ = true;  // the actuators refused it (their rate limit) and hold
  for (int i = 0; i < actuators_; ++i) {
    if (holding_) {
      out.measured_displacement[i] = service_->held_position(i);
      out.measured_force[i] = 0.0;
    } else {
      out.measured_displacement[i] = paced() ? plant_realised_[i] : feedback.realised(i);
      out.measured_force[i] = paced() ? plant_force_[i] : feedback.force(i);
    }
  }
  if (holding_) out.status = controller_node::kStatusHold;
  std::vector<std::uint8_t> bytes;
  if (!controller_node::encode(link_.feedback(), out, bytes)) {
    ++counts_.rejected;
    spdlog::error("controller emulator: feedback of frame {} does not fit its frame", in.counter);
    return std::nullopt;
  }
  ++counts_.answered;
  return bytes;
}

// A HOLD frame's answer: status HOLD (held) and where the actuators hold.
std::optional<std::vector<std::uint8_t>> ControllerEmulator::held_answer(const FrameValues& in) {
  FrameValues out = in;
  out.status = controller_node::kStatusHold;
  for (int i = 0; i < actuators_; ++i) {
    out.measured_displacement[i] = service_->held_position(i);
    out.measured_force[i] = 0.0;
  }
  std::vector<std::uint8_t> bytes;
  if (!controller_node::encode(link_.feedback(), out, bytes)) return std::nullopt;
  return bytes;
}

bool ControllerEmulator::command_actuators(const FrameValues& in, runtime::Feedback& feedback) {
  runtime::Command command;
  command.set_time(in.time);
  for (int i = 0; i < actuators_; ++i) {
    command.add_drift(in.target_displacement[i]);
    command.add_drift_velocity(in.target_velocity[i]);
  }
  const auto replies = service_->handle(
      runtime::pack(kRunId, service_->node_id(), runtime::COMMAND, ++step_, command));
  // Paced, a loaded command has no reply (its answers are the ticks); a reply is its HOLD.
  if (paced()) return replies.empty() && service_->last_step() == step_;
  return !replies.empty() && replies.front().kind == runtime::FEEDBACK &&
         runtime::unpack(replies.front(), feedback);
}

void ControllerEmulator::tick(bool overrun) {
  ++counts_.ticks;
  if (overrun) ++counts_.overruns;
  const auto sample = service_->servo_tick(overrun);
  runtime::Feedback feedback;
  if (!sample || !runtime::unpack(*sample, feedback)) return;  // at rest or holding
  for (int i = 0; i < actuators_ && i < feedback.realised_size(); ++i) {
    plant_realised_[i] = feedback.realised(i);
    plant_force_[i] = feedback.force(i);
  }
}

namespace {

// The plant's own clock (paced only): one tick() per plant period on absolute deadlines until
// `done`, each under `lock` so that a command frame never sees half a period.
class PlantThread {
 public:
  PlantThread(ControllerEmulator& emulator, std::mutex& lock) {
    if (!emulator.paced()) return;
    thread_ = std::thread([this, &emulator, &lock] {
      runtime::MonotonicClock clock;
      runtime::Pacer pacer(clock, emulator.plant_period(), emulator.wait_policy());
      pacer.start();
      for (std::int64_t k = 1; !done_; ++k) {
        const runtime::PaceResult pace = pacer.wait(k);
        std::lock_guard guard(lock);
        emulator.tick(pace.overrun);
      }
    });
  }
  ~PlantThread() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }
  PlantThread(const PlantThread&) = delete;
  PlantThread& operator=(const PlantThread&) = delete;

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

void log_start(const ControllerEmulator& emulator, const controller_node::UdpLink& udp,
               double answer_lag) {
  spdlog::info("controller emulator: listening on {}, answering {}", udp.local(), udp.peer());
  if (emulator.paced())
    spdlog::info("controller emulator: plant paced at {:.0f} Hz (wait policy {})",
                 1.0 / emulator.plant_period(), runtime::to_string(emulator.wait_policy().kind));
  else
    spdlog::info("controller emulator: each command frame is one step of the actuators");
  if (answer_lag > 0)
    spdlog::info("controller emulator: each answer leaves {:.3f} ms after its frame arrived",
                 answer_lag * 1e3);
}

// Answers waiting for their lag, in arrival order (a link does not reorder): each leaves
// answer_lag after its frame was read (ns, CLOCK_MONOTONIC), and at least answer_period after
// the one before, however many are in flight.
class DelayedAnswers {
 public:
  DelayedAnswers(controller_node::UdpLink& udp, std::int64_t lag_ns, std::int64_t period_ns)
      : udp_(udp), lag_ns_(lag_ns), period_ns_(period_ns) {}
  bool empty() const { return pending_.empty(); }
  std::int64_t next_ns() const { return pending_.front().first; }
  void send_due(std::int64_t now) {
    while (!pending_.empty() && pending_.front().first <= now) {
      udp_.send(pending_.front().second.data(), pending_.front().second.size());
      pending_.pop_front();
    }
  }
  // The answer to a frame read at `received_ns`: sent now when its time has come and none
  // waits before it, else queued.
  void add(std::int64_t received_ns, std::vector<std::uint8_t> answer) {
    const std::int64_t release = std::max(received_ns + lag_ns_, last_release_ns_ + period_ns_);
    last_release_ns_ = release;
    if (release <= controller_node::monotonic_ns() && pending_.empty()) {
      udp_.send(answer.data(), answer.size());
      return;
    }
    pending_.emplace_back(release, std::move(answer));
  }

 private:
  controller_node::UdpLink& udp_;
  std::int64_t lag_ns_, period_ns_, last_release_ns_ = 0;
  std::deque<std::pair<std::int64_t, std::vector<std::uint8_t>>> pending_;
};

// Every queued frame stepped through the emulator (under `lock`, shared with the plant thread)
// and its answer handed to `answers`; a frame from any host but the peer is named and ignored.
// `last_frame_ns`: when the newest frame was read.
void answer_frames(ControllerEmulator& emulator, controller_node::UdpLink& udp, std::mutex& lock,
                   DelayedAnswers& answers, std::int64_t& last_frame_ns) {
  controller_node::Datagram d;
  while (udp.try_receive(d)) {
    last_frame_ns = d.received_ns;
    if (!d.from_peer) {
      spdlog::warn("controller emulator: frame from {} ignored (not the host {})",
                   controller_node::source_text(d), udp.peer());
      continue;
    }
    std::unique_lock guard(lock);
    auto answer = emulator.step(d.bytes.data(), std::min(d.size, d.bytes.size()));
    guard.unlock();
    if (answer) answers.add(d.received_ns, std::move(*answer));
  }
}

}  // namespace

int serve(ControllerEmulator& emulator, double idle_timeout, double answer_lag,
          double answer_period) {
  const config::ControllerLink& link = emulator.link();
  controller_node::UdpLink udp(link.peer_address(), link.peer_port(), link.local_address(),
                               link.local_port());
  log_start(emulator, udp, answer_lag);
  const auto idle_ns = static_cast<std::int64_t>(idle_timeout * 1e9);
  const auto lag_ns = static_cast<std::int64_t>(std::llround(answer_lag * 1e9));
  const auto period_ns = static_cast<std::int64_t>(std::llround(answer_period * 1e9));
  runtime::MonotonicClock clock;
  // The lag's sleep ends on time, not up to the kernel's default 50 us of timer slack later.
  if (lag_ns > 0 || period_ns > 0) prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  std::mutex lock;
  int result = 0;
  {
    PlantThread plant(emulator, lock);
    DelayedAnswers answers(udp, lag_ns, period_ns);
    std::int64_t last_frame_ns = controller_node::monotonic_ns();
    while (!emulator.stopped() || !answers.empty()) {
      const std::int64_t now = controller_node::monotonic_ns();
      answers.send_due(now);
      if (emulator.stopped()) {
        if (!answers.empty()) clock.sleep_until_ns(answers.next_ns());
        continue;
      }
      if (now - last_frame_ns > idle_ns) {
        spdlog::error("controller emulator: no frame for {} s; leaving", idle_timeout);
        result = 1;
        break;
      }
      const std::int64_t wake = answers.empty() ? last_frame_ns + idle_ns + 1 : answers.next_ns();
      if (udp.wait(wake)) answer_frames(emulator, udp, lock, answers, last_frame_ns);
    }
  }
  const EmulatorCounts& c = emulator.counts();
  spdlog::info(
      "controller emulator: {}; {} command frames, {} answered, {} HOLD, {} rejected; plant "
      "periods {}, overruns {}",
      result == 0 ? "stopped" : "left", c.commands, c.answered, c.holds, c.rejected, c.ticks,
      c.overruns);
  return result;
}

}  // namespace rths::controller_emulator
