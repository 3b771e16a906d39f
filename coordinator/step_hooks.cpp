// Pacing before a step, the real-time thread and the record after it (see state.h).
#include "coordinator/state.h"

#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "runtime/node/plan.h"
#include "runtime/rt/clock.h"
#include "study/study_inputs.h"
#include "transport/dds_endpoint.h"
#include "util/crc32c.h"
#include "util/process.h"

namespace rths::coordinator {

void RunState::event(const std::string& what) {
  spdlog::info("step {}: {}", step, what);
  if (!record) return;
  runtime::RecordEntry entry;
  entry.mutable_event()->set_step(step);
  entry.mutable_event()->set_what(what);
  entry.mutable_event()->set_realtime_ns(transport::realtime_ns());
  record->append(entry);  // a full queue drops it and counts it, as for steps
}

void RunState::apply_presses() {
  std::optional<std::string> stop, hold;
  for (const view::Press& press : options.control->take()) {
    if (press.allowed && !press.hold_nodes.empty()) {
      runtime::Hold hold_message;
      hold_message.set_reason("HOLD from the view by " + press.who);
      for (const int id : press.hold_nodes)
        if (const auto node = nodes.find(id); node != nodes.end() && node->second.announced)
          send(id, runtime::HOLD, step, hold_message);
    }
    // How long the press took to reach the loop (and an allowed HOLD its nodes): in steps from the
    // newest the view had seen (the loop was at least there), and in CLOCK_REALTIME of this host.
    event(
        fmt::format("{} (applied at step {}, the view had seen step {}; {:.2f} ms after the press)",
                    press.text(), step, press.seen_step,
                    static_cast<double>(transport::realtime_ns() - press.realtime_ns) * 1e-6));
    if (!press.allowed) continue;
    if (press.stop && !stop) stop = std::string(kStoppedFromView) + " by " + press.who;
    if (!press.stop && !hold) hold = "HOLD from the view by " + press.who;
  }
  if (stop)
    throw RunAborted(held_from_view.empty() ? *stop : *stop + " (held: " + held_from_view + ")",
                     "");
  if (hold && held_from_view.empty()) hold_run(*hold);
}

void RunState::hold_run(const std::string& why) {
  held_from_view = why;
  // "HOLD ..." first: the view's state turns HOLD with this as its reason.
  event(fmt::format(
      "HOLD of the run at step {}: {}; no further step is integrated and no command leaves (the "
      "held actuators hold where they stand, every other lab's stay at their last command) "
      "until the director's STOP",
      step, why));
  for (;;) {
    if (options.stop_request && options.stop_request->load(std::memory_order_relaxed))
      throw RunAborted(std::string(kStoppedFromView) + " (held: " + why + ")", "");
    if (options.control->pending()) apply_presses();
    pump(std::chrono::milliseconds(10));
    while (pump(std::chrono::nanoseconds::zero())) {}
    check_liveliness();
  }
}

void RunState::before_step(std::size_t k) {
  pace = {};
  // One timed wait per period, the pacer's: feedback is stamped and boxed on the receive thread
  // meanwhile, and other messages wait in the transport's queue (stamped on arrival). No second
  // timed wait here: each late wake-up of one would be an overrun.
  if (real_time) {
    pace = pacer->wait(static_cast<std::int64_t>(k));
    // What queued during the wait (an emulator's HOLD stops the run before the next command).
    while (pump(std::chrono::nanoseconds::zero())) {}
  }
  step = static_cast<std::int64_t>(k);
  if (options.stop_request && options.stop_request->load(std::memory_order_relaxed))
    throw RunAborted(kStoppedFromView, "");
  if (options.control && options.control->pending()) apply_presses();
  intake->await_step(step);
  step_start = Clock::now();
  step_start_realtime_ns = transport::realtime_ns();
  step_cpu_start = runtime::thread_cpu_ns();
}

bool RunState::after_step(std::size_t k, const core::SimulationResult& result) {
  const double step_wall = k == 0 ? 0.0 : seconds_since(step_start);
  if (k > 0)
    step_cpu.push_back(static_cast<double>(runtime::thread_cpu_ns() - step_cpu_start) * 1e-9);
  write_step(k, result, step_wall);
  check_record();
  if (k > 0)
    for (auto& [id, node] : nodes) lags.add(result.time[k], link_of(id));
  if (k == 0) {
    last_heartbeat_sent = Clock::now();
    for (auto& [id, node] : nodes) node.last_seen = Clock::now();
    if (real_time) pacer->start();
  }
  return true;
}

void RunState::check_record() {
  if (!record) return;
  if (record->failed()) {
    record_failed = true;
    throw RunAborted(record->failure(), "");
  }
  if (record->dropped() > 0) {
    record_failed = true;
    throw RunAborted("the run record's writer fell more than " +
                         std::to_string(record->capacity()) + " entries behind (" +
                         std::to_string(record->dropped()) + " dropped)",
                     "");
  }
}

void RunState::prepare_real_time_thread() {
  if (deployment.lock_memory()) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
      event(std::string("mlockall refused (") + std::strerror(errno) + "); memory not locked");
    else
      event("memory locked (mlockall)");
  }
  if (deployment.pin_loop()) {
    // The CPU is the loop's alone: a receive thread woken on it would preempt the loop between
    // its commands (README "Real time" has the wake-up to command figures).
    try {
      util::isolate_calling_thread_on_cpu(deployment.loop_cpu());
      event("loop thread alone on CPU " + std::to_string(deployment.loop_cpu()) +
            " (the process's other threads moved off it)");
    } catch (const std::runtime_error& e) {
      event(std::string("loop thread not isolated: ") + e.what());
    }
  }
  if (const int priority = runtime::realtime_priority(deployment); priority > 0) {
    fifo.emplace(priority, "loop", transport::dds_receive_thread_names());
    event(fifo->summary());
  }
}

void RunState::write_header() {
  if (!record) return;
  runtime::RecordEntry entry;
  runtime::RunHeader& h = *entry.mutable_header();
  h.set_schema_version(runtime::kSchemaVersion);
  h.set_run_id(options.run_id);
  *h.mutable_study() = prepared.config;
  h.set_case_name(case_name);
  h.set_clock(real_time ? "real_time" : "lockstep");
  h.set_dt(setup.dt);
  h.set_dofs(setup.model.dofs());
  h.set_actuators(static_cast<int>(setup.partition.actuator_storeys.size()));
  // The DOFs each step keeps: the recorders' (coordinator.cpp, loop), or every DOF (none named)
  // when an outside driver sizes the result.
  if (!options.driver)
    for (const int dof : prepared.recorders.kept_dofs) h.add_recorded_dofs(dof);
  for (auto& [id, node] : nodes) h.add_link_node_ids(id);
  h.set_start_realtime_ns(transport::realtime_ns());
  h.set_timestamp_clock(
      "CLOCK_REALTIME ns; round_trip uses the coordinator's clock only, one-way lags "
      "include the clock offset between hosts");
  if (options.platform) *h.mutable_platform() = *options.platform;
  // The record carries its inputs (motion as run, matrices, traces) in an entry of their own, so
  // it reads anywhere and a damaged inputs entry loses nothing else; each header copy names them.
  runtime::RecordEntry inputs;
  *inputs.mutable_inputs()->mutable_study() = study::with_embedded_inputs(prepared);
  const std::string inputs_bytes = inputs.SerializeAsString();
  h.set_inputs_crc32c(util::crc32c(inputs_bytes.data(), inputs_bytes.size()));
  append_waiting(entry);
  header_entry = std::move(entry);
  append_waiting(inputs);
}

void RunState::write_step(std::size_t k, const core::SimulationResult& result, double step_wall) {
  if (!record) return;
  runtime::StepRecord& r = step_record;
  r.Clear();  // keeps the repeated fields' storage
  const auto row = static_cast<Eigen::Index>(k);
  r.set_step(static_cast<std::int64_t>(k));
  r.set_time(result.time[k]);
  r.set_ground_acceleration(prepared.motion.acceleration[k]);
  for (int i = 0; i < result.displacement.cols(); ++i) {
    r.add_displacement(result.displacement(row, i));
    r.add_velocity(result.velocity(row, i));
    r.add_acceleration(result.acceleration(row, i));
  }
  for (int a = 0; a < result.command.cols(); ++a) {
    r.add_command(result.command(row, a));
    r.add_realised(result.realised(row, a));
    r.add_measured_force(result.measured_force(row, a));
  }
  if (k > 0)
    for (auto& [id, node] : nodes) {
      runtime::LinkSample* link = r.add_links();
      *link = link_of(id);
      if (!predictors.empty() && runtime::drives_actuators(node.plan->spec.kind()))
        for (int a : node.plan->actuators)
          link->add_prediction_error(result.prediction_error(row, a));
    }
  r.set_lateness(pace.lateness);
  r.set_step_wall(step_wall);
  r.set_command_latency(
      k == 0 ? 0.0 : std::chrono::duration<double>(commands_written - step_start).count());
  r.set_overrun(pace.overrun);
  r.set_start_realtime_ns(k == 0 ? 0 : step_start_realtime_ns);
  step_entry.unsafe_arena_set_allocated_step(&step_record);
  record->append(step_entry);
  step_entry.unsafe_arena_release_step();
}

}  // namespace rths::coordinator
