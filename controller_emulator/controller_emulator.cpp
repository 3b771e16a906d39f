#include "controller_emulator/controller_emulator.h"

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "controller_node/controller_exchange.h"
#include "controller_node/frame.h"
#include "controller_node/udp_link.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"

namespace rths::controller_emulator {
namespace {

using controller_node::Direction;
using controller_node::FrameValues;
using controller_node::FrameVerdict;

const char* const kRunId = "controller-emulator";

// The Assign the coordinator would send the node, as an actuator emulator's: the node's own
// delay stages and link lags left out (the controller node applies those itself), and the clock
// lockstep, so the actuators answer each command once (their servo periods in simulated time).
runtime::Assign assignment(const config::Study& study, const std::filesystem::path& base_dir,
                           const std::string& case_name, int node_id) {
  const core::PreparedStudy prepared = core::prepare_study(study, base_dir);
  const config::Case& study_case = runtime::find_case(study, case_name);
  const core::HybridSetup setup = core::setup_for_case(prepared, study_case);
  const config::Deployment deployment = runtime::with_default_nodes(study.deployment(), setup);
  const runtime::DeploymentPlan plan = runtime::make_plan(setup, deployment);
  const runtime::NodePlan* node = plan.find(node_id);
  if (!node || node->spec.kind() != config::NodeSpec::CONTROLLER)
    throw std::invalid_argument("node " + std::to_string(node_id) +
                                " is not a CONTROLLER of the study's deployment");
  runtime::Assign assign;
  assign.set_schema_version(runtime::kSchemaVersion);
  *assign.mutable_study() = study;
  assign.mutable_study()->mutable_deployment()->set_clock(config::Deployment::LOCKSTEP);
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
  controller_node::check_layout(link_.command(), actuators_, Direction::kCommand,
                                "controller.command");
  controller_node::check_layout(link_.feedback(), actuators_, Direction::kFeedback,
                                "controller.feedback");
  for (const auto* layout : {&link_.command(), &link_.feedback()})
    if (controller_node::frame_size(*layout) > controller_node::kMaxDatagram)
      throw std::invalid_argument("controller: a frame longer than a datagram is read");
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
    spdlog::warn("controller emulator: status HOLD received (frame {}); actuators hold",
                 in.counter);
    service_->handle(runtime::pack(kRunId, id, runtime::HOLD, step_, runtime::Hold{}));
    service_->settle_hold();
    holding_ = true;
    return std::nullopt;
  }
  ++counts_.commands;
  if (answer_frames_ >= 0 && static_cast<std::int64_t>(counts_.answered) >= answer_frames_)
    return std::nullopt;  // gone silent
  runtime::Command command;
  command.set_time(in.time);
  for (int i = 0; i < actuators_; ++i) {
    command.add_drift(in.target_displacement[i]);
    command.add_drift_velocity(in.target_velocity[i]);
  }
  FrameValues out = in;
  out.status = controller_node::kStatusRun;
  runtime::Feedback feedback;
  if (!holding_) {
    const auto replies =
        service_->handle(runtime::pack(kRunId, id, runtime::COMMAND, ++step_, command));
    if (replies.empty() || replies.front().kind != runtime::FEEDBACK ||
        !runtime::unpack(replies.front(), feedback))
      holding_ = true;  // the actuators refused it (their rate limit) and hold
  }
  if (holding_) {
    out.status = controller_node::kStatusHold;
    for (int i = 0; i < actuators_; ++i) {
      out.measured_displacement[i] = service_->held_position(i);
      out.measured_force[i] = 0.0;
    }
  } else {
    for (int i = 0; i < actuators_; ++i) {
      out.measured_displacement[i] = feedback.realised(i);
      out.measured_force[i] = feedback.force(i);
    }
  }
  std::vector<std::uint8_t> bytes;
  if (!controller_node::encode(link_.feedback(), out, bytes)) {
    ++counts_.rejected;
    spdlog::error("controller emulator: feedback of frame {} does not fit its frame", in.counter);
    return std::nullopt;
  }
  ++counts_.answered;
  return bytes;
}

int serve(ControllerEmulator& emulator, double idle_timeout) {
  const config::ControllerLink& link = emulator.link();
  controller_node::UdpLink udp(link.peer_address(), link.peer_port(), link.local_address(),
                               link.local_port());
  spdlog::info("controller emulator: listening on {}, answering {}", udp.local(), udp.peer());
  const auto idle_ns = static_cast<std::int64_t>(idle_timeout * 1e9);
  while (!emulator.stopped()) {
    const auto d = udp.receive(controller_node::monotonic_ns() + idle_ns);
    if (!d) {
      spdlog::error("controller emulator: no frame for {} s; leaving", idle_timeout);
      return 1;
    }
    if (!d->from_peer) {
      spdlog::warn("controller emulator: frame from {} ignored (not the host {})", d->source,
                   udp.peer());
      continue;
    }
    if (auto answer = emulator.step(d->bytes.data(), d->size)) udp.send(*answer);
  }
  const EmulatorCounts& c = emulator.counts();
  spdlog::info("controller emulator: stopped; {} command frames, {} answered, {} HOLD, {} rejected",
               c.commands, c.answered, c.holds, c.rejected);
  return 0;
}

}  // namespace rths::controller_emulator
