#include "tests/support/fault_trial.h"

#include <signal.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include "runtime/record/record.h"
#include "security/run_secret.h"
#include "tests/support/log_stamps.h"
#include "transport/transport.h"
#include "util/process.h"

namespace rths::test {
namespace {

using namespace std::chrono_literals;

std::string label(FaultVictim v) {
  switch (v) {
    case FaultVictim::kSubstructure: return "node 1 (substructure)";
    case FaultVictim::kEmulator: return "node 2 (actuator emulator)";
    default: return "coordinator";
  }
}

}  // namespace

std::string to_string(FaultVictim victim) {
  switch (victim) {
    case FaultVictim::kCoordinator: return "coordinator";
    case FaultVictim::kSubstructure: return "substructure";
    case FaultVictim::kEmulator: return "emulator";
  }
  return "?";
}

FaultTrialResult run_fault_trial(const FaultTrialSpec& spec) {
  std::filesystem::remove_all(spec.dir);
  std::filesystem::create_directories(spec.dir);
  const auto config = spec.dir / "study.textproto";
  std::ofstream(config)
      << "name: \"fault_trial\"\n"
         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \""
      << spec.motion_path << "\" duration: " << spec.seconds << " }\n"
      << "integrator { kind: EXPLICIT_NEWMARK dt: " << 1.0 / spec.rate_hz << " }\n"
      << "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"reference\" }\n"
         "deployment { clock: REAL_TIME max_overrun_fraction: -1 "
      << spec.deployment_extra << " }\n";
  const auto record = spec.dir / "run.rthsrec";
  const std::string run_id = "fault-trial-" + std::to_string(spec.domain);
  // Every process gets the run secret in its environment, as `rths launch` hands it down.
  util::ChildOptions trusted;
  trusted.environment = {{security::kSecretEnv, security::generate_run_secret()}};
  const auto node = [&](const std::string& program, const std::string& subdir, int id) {
    return util::ChildProcess(spec.binary_dir / subdir / program,
                              {"--node-id", std::to_string(id), "--domain",
                               std::to_string(spec.domain), "--run-id", run_id},
                              spec.dir / ("node_" + std::to_string(id) + ".log"), trusted);
  };
  util::ChildProcess substructure = node("rths-substructure-node", "substructure_nodes", 1);
  util::ChildProcess emulator = node("rths-actuator-emulator", "actuator_emulator", 2);
  std::vector<std::string> coordinator_args{
      "--config", config.string(), "--run-id", run_id, "--domain", std::to_string(spec.domain),
      "--record", record.string()};
  coordinator_args.insert(coordinator_args.end(), spec.coordinator_extra.begin(),
                          spec.coordinator_extra.end());
  util::ChildProcess coordinator(spec.binary_dir / "coordinator" / "rths-coordinator",
                                 coordinator_args, spec.dir / "coordinator.log", trusted);
  util::ChildProcess& victim = spec.victim == FaultVictim::kCoordinator    ? coordinator
                               : spec.victim == FaultVictim::kSubstructure ? substructure
                                                                           : emulator;
  FaultTrialResult out;
  // Wait for the fault step.
  const auto give_up = std::chrono::steady_clock::now() + 30s;
  for (;;) {
    if (!coordinator.running()) {
      out.why_not = "the run ended before step " + std::to_string(spec.fault_step) + ": " +
                    read_text(spec.dir / "coordinator.log");
      try {
        out.record_steps = static_cast<long>(runtime::read_record(record).steps().size());
      } catch (const std::exception&) {
        out.record_steps = 0;  // no record: the run stopped before its first step
      }
      return out;
    }
    if (std::filesystem::exists(record)) {
      try {
        if (static_cast<long>(runtime::read_record(record).steps().size()) >= spec.fault_step)
          break;
      } catch (const std::exception&) {
        // A partly written entry mid-read: try again.
      }
    }
    if (std::chrono::steady_clock::now() > give_up) {
      out.why_not = "the run never reached step " + std::to_string(spec.fault_step);
      return out;
    }
    std::this_thread::sleep_for(2ms);
  }
  const std::int64_t fault_ns = transport::realtime_ns();
  victim.signal(spec.signal);
  out.fault_delivered = true;

  if (spec.victim != FaultVictim::kCoordinator) {
    out.coordinator_exit = coordinator.wait_for(10s).value_or(-2);
  } else {
    // The nodes hold on their watchdog and leave on their orphan timeout.
    emulator.wait_for(10s);
    substructure.wait_for(10s);
  }
  if (spec.signal == SIGSTOP) victim.signal(SIGKILL);
  for (util::ChildProcess* p : {&coordinator, &substructure, &emulator}) {
    if (!p->wait_for(3s)) p->signal(SIGKILL);
    p->wait_for(3s);
  }

  const std::string coordinator_log = read_text(spec.dir / "coordinator.log");
  const std::string emulator_log = read_text(spec.dir / "node_2.log");
  if (spec.victim != FaultVictim::kEmulator)
    if (auto hold = stamped_line(emulator_log, "HOLD");
        hold || (hold = stamped_line(emulator_log, "holding")))
      out.hold_ms = static_cast<double>(*hold - fault_ns) * 1e-6;
  out.names_node = spec.victim == FaultVictim::kCoordinator
                       ? emulator_log.find("command watchdog") != std::string::npos
                       : coordinator_log.find(label(spec.victim)) != std::string::npos;

  try {
    const runtime::RecordContents contents = runtime::read_record(record);
    const auto steps = contents.steps();
    out.record_steps = static_cast<long>(steps.size());
    bool contiguous = true;
    long before_fault = 0;
    std::int64_t first_start = 0;
    const int victim_id = spec.victim == FaultVictim::kSubstructure ? 1 : 2;
    std::int64_t victim_answered = -1;
    std::size_t last_answer_step = 0;
    for (std::size_t k = 0; k < steps.size(); ++k) {
      contiguous = contiguous && steps[k]->step() == static_cast<long>(k);
      for (const auto& link : steps[k]->links())
        if (link.node_id() == victim_id && link.answered_step() > victim_answered) {
          victim_answered = link.answered_step();
          last_answer_step = k;
        }
      const std::int64_t start = steps[k]->start_realtime_ns();
      if (k == 1) first_start = start;
      if (k > 0 && start > fault_ns) ++out.steps_after_fault;
      if (k == 0 || start <= fault_ns) ++before_fault;
    }
    if (spec.victim != FaultVictim::kCoordinator && !steps.empty())
      out.steps_unanswered = static_cast<long>(steps.size() - 1 - last_answer_step);
    for (const auto& e : contents.entries)
      if (e.has_event() && e.event().what().rfind("HOLD sent", 0) == 0)
        out.stop_ms = static_cast<double>(e.event().realtime_ns() - fault_ns) * 1e-6;
    // Steps that must be there: step 0 and every step begun by the fault. A surviving
    // coordinator writes on past the fault, so a gapless record with steps after it holds them
    // all. A killed one may lose the step in progress and its writer's queue: at most the steps
    // the deadline grid allows since its first step (an upper bound, also when steps overran).
    bool holds_begun = out.steps_after_fault > 0;
    if (spec.victim == FaultVictim::kCoordinator) {
      const double dt_ns = 1e9 / spec.rate_hz;
      const long begun =
          first_start > 0
              ? 1 + static_cast<long>(static_cast<double>(fault_ns - first_start) / dt_ns)
              : 0;
      holds_begun = before_fault + 4096 + 1 >= begun;
    }
    out.record_complete = contiguous && holds_begun && before_fault >= spec.fault_step;
  } catch (const std::exception& e) {
    out.record_complete = false;
    out.why_not = std::string("record unreadable: ") + e.what();
  }
  return out;
}

}  // namespace rths::test
