#include "tests/support/controller_trial.h"

#include <signal.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include "deploy/netns.h"
#include "runtime/launch/launch.h"
#include "runtime/node/plan.h"
#include "runtime/record/record.h"
#include "study/study.h"
#include "tests/controller_node/link_text.h"
#include "tests/support/log_stamps.h"
#include "transport/transport.h"
#include "util/process.h"

namespace rths::test {
namespace {

using namespace std::chrono_literals;

std::string study_text(const ControllerTrialSpec& spec, const std::string& host,
                       const std::string& rig) {
  std::ostringstream t;
  t.precision(17);
  t << "name: \"controller_rt\"\n"
       "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
       "motion { path: \""
    << spec.motion_path << "\" duration: " << spec.seconds << " }\n"
    << "integrator { kind: EXPLICIT_NEWMARK dt: " << 1.0 / spec.rate_hz << " }\n"
    << "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
    << "servo { rate: " << spec.plant_hz << " }\n"
    << "cases { name: \"reference\" }\n"
    << "deployment { clock: REAL_TIME answer_window_ms: " << spec.answer_window_ms
    << " command_watchdog_ms: " << spec.answer_window_ms
    << " limits { max_displacement: 0.2 max_velocity: 2.0 }"
    << " nodes { id: 2 kind: CONTROLLER controller { local_address: \"" << host
    << "\" local_port: " << spec.node_port << " peer_address: \"" << rig
    << "\" peer_port: " << spec.peer_port << " max_force: 20000 " << kCommandFields << " "
    << kFeedbackFields << " } } " << spec.deployment_extra << " }\n";
  return t.str();
}

// Waits until the record holds fault_step steps (or the run is over), then signals the victim.
void deliver_fault(const ControllerTrialSpec& spec, const std::filesystem::path& record,
                   const util::ChildProcess& emulator, const std::atomic<bool>& run_over,
                   std::int64_t& fault_ns) {
  const int sig = spec.fault == ControllerFault::kKill ? SIGKILL : SIGSTOP;
  while (!run_over) {
    try {
      if (std::filesystem::exists(record) &&
          static_cast<long>(runtime::read_record(record).steps().size()) >= spec.fault_step) {
        fault_ns = transport::realtime_ns();
        emulator.signal(sig);
        return;
      }
    } catch (const std::exception&) {
      // A partly written entry mid-read: try again.
    }
    std::this_thread::sleep_for(2ms);
  }
}

// The coordinator and the controller node at site "host", DDS on its loopback; no platform
// measurement (recorded so).
runtime::LaunchOptions launch_options(const ControllerTrialSpec& spec,
                                      const std::filesystem::path& config,
                                      const deploy::NamespaceTopology& topology) {
  runtime::LaunchOptions launch;
  launch.config = config;
  launch.record = spec.dir / "run.rthsrec";
  launch.log_dir = spec.dir;
  launch.domain = spec.domain;
  launch.timeout = spec.seconds + 60;
  launch.programs_dir = spec.binary_dir;
  launch.cpu_placement = runtime::CpuPlacement::kSpread;
  launch.platform_seconds = 0;
  launch.accept_platform = true;
  launch.placement = [prefix = topology.exec_prefix("host")](int) {
    return runtime::Placement{
        prefix, {{"CYCLONEDDS_URI", runtime::kLoopbackDdsConfig}}, "site host"};
  };
  return launch;
}

// The run, with the spec's fault delivered to the emulator meanwhile (fault_ns: when; 0 = never).
runtime::LaunchResult launch_with_fault(const ControllerTrialSpec& spec,
                                        const runtime::LaunchOptions& launch,
                                        const util::ChildProcess& emulator,
                                        std::int64_t& fault_ns) {
  std::atomic<bool> run_over{false};
  std::thread fault;
  if (spec.fault != ControllerFault::kNone)
    fault = std::thread([&] { deliver_fault(spec, launch.record, emulator, run_over, fault_ns); });
  runtime::LaunchResult launched;
  try {
    launched = runtime::launch_run(launch);
  } catch (...) {
    run_over = true;
    if (fault.joinable()) fault.join();
    throw;
  }
  run_over = true;
  if (fault.joinable()) fault.join();
  return launched;
}

// One sample per fresh answer of node 2 (its answered step advanced).
void read_round_trips(const runtime::RecordContents& contents, ControllerTrialResult& out) {
  std::vector<double> controller, dds;
  std::int64_t answered = 0;
  for (const runtime::StepRecord* step : contents.steps())
    for (const auto& link : step->links())
      if (link.node_id() == 2 && link.answered_step() > answered) {
        answered = link.answered_step();
        controller.push_back(link.controller_round_trip());
        dds.push_back(link.round_trip());
      }
  out.controller_round_trip = runtime::summarize(controller);
  out.round_trip = runtime::summarize(dds);
}

void read_outcome(const ControllerTrialSpec& spec, const std::filesystem::path& record,
                  std::int64_t fault_ns, ControllerTrialResult& out) {
  std::optional<std::int64_t> hold;
  try {
    const runtime::RecordContents contents = runtime::read_record(record);
    out.record_steps = static_cast<long>(contents.steps().size());
    if (const auto* footer = contents.footer()) out.status = footer->status();
    read_round_trips(contents, out);
    for (const auto& e : contents.entries)
      if (e.has_event() && e.event().what().rfind("HOLD sent", 0) == 0 && !hold)
        hold = e.event().realtime_ns();
  } catch (const std::exception& e) {
    out.status = std::string("record unreadable: ") + e.what();
  }
  const std::string node_log = read_text(spec.dir / "node_2.log");
  const std::string emulator_log = read_text(spec.dir / "emulator.log");
  if (const auto own = stamped_line(node_log, "holding on its own"); own && (!hold || *own < *hold))
    hold = own;
  if (hold && fault_ns > 0) out.hold_ms = static_cast<double>(*hold - fault_ns) * 1e-6;
  out.hold_frame_sent =
      node_log.find("HOLD frames (status 1) to the controller") != std::string::npos;
  out.hold_frame_received = emulator_log.find("status HOLD received") != std::string::npos;
  std::smatch m;
  static const std::regex plant("plant periods ([0-9]+), overruns ([0-9]+)");
  if (std::regex_search(emulator_log, m, plant)) {
    out.plant_periods = std::stoull(m[1]);
    out.plant_overruns = std::stoull(m[2]);
  }
}

}  // namespace

std::string to_string(ControllerFault fault) {
  switch (fault) {
    case ControllerFault::kNone: return "none";
    case ControllerFault::kKill: return "SIGKILL";
    case ControllerFault::kStop: return "SIGSTOP";
  }
  return "?";
}

ControllerTrialResult run_controller_trial(const ControllerTrialSpec& spec) {
  std::filesystem::remove_all(spec.dir);
  std::filesystem::create_directories(spec.dir);
  deploy::remove_stale_namespaces();
  deploy::NamespaceTopology topology({{"host", "rig"}, spec.subnet});
  const auto config = spec.dir / "study.textproto";
  const std::string text =
      study_text(spec, topology.site("host").address, topology.site("rig").address);
  std::ofstream(config) << text;
  const config::Study study = study::parse_study(text, config.string());
  ControllerTrialResult out;
  const int window = runtime::max_missed_answers(study.deployment(), 1.0 / spec.rate_hz);
  out.window_ms = window * 1e3 / spec.rate_hz;

  util::ChildOptions at_rig;
  at_rig.prefix = topology.exec_prefix("rig");
  std::ostringstream lag;
  lag << spec.answer_lag_ms;
  util::ChildProcess emulator(spec.binary_dir / "controller_emulator" / "rths-controller-emulator",
                              {"--config", config.string(), "--node-id", "2", "--answer-lag-ms",
                               lag.str(), "--idle-timeout", "30"},
                              spec.dir / "emulator.log", at_rig);
  std::int64_t fault_ns = 0;
  const runtime::LaunchResult launched =
      launch_with_fault(spec, launch_options(spec, config, topology), emulator, fault_ns);
  out.coordinator_exit = launched.coordinator_exit;
  out.fault_delivered = fault_ns > 0;
  if (spec.fault != ControllerFault::kNone && !out.fault_delivered)
    out.why_not = "the run ended before step " + std::to_string(spec.fault_step) + ": " +
                  launched.coordinator_log_tail;
  if (spec.fault == ControllerFault::kStop) emulator.signal(SIGCONT);
  out.emulator_exit = emulator.wait_for(5s).value_or(-1);
  if (out.emulator_exit < 0) out.emulator_exit = emulator.terminate();
  read_outcome(spec, spec.dir / "run.rthsrec", fault_ns, out);
  return out;  // the namespaces are removed here, after every process has left
}

}  // namespace rths::test
